#!/bin/bash
# Installs the liveprobe build BUILD into a temporary prefix, builds tests/consumer against it
# with find_package(liveprobe), and runs its three programs. Usage: run.sh BUILD DATA_DIR
set -euo pipefail
build=$1 data=$2
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" > "$work/install.log"
cmake -S "$here" -B "$work/build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$work/prefix" \
  > "$work/configure.log" || { cat "$work/configure.log"; exit 1; }
cmake --build "$work/build" -j 2 > "$work/build.log" || { cat "$work/build.log"; exit 1; }
# The SH core brings nothing with it: no OpenCV, GL or GLFW in the sh_only program.
if ldd "$work/build/sh_only" | grep -E 'opencv|libGL|glfw|OSMesa|assimp'; then
  echo "consumer: sh_only links more than the standard library" >&2
  exit 1
fi
"$work/build/sh_only"
"$work/build/grace" "$data/probes/latlong_full/grace_latlong.exr"
"$work/build/exchange_json" "$data/probes/latlong_full/grace_latlong.exr"
