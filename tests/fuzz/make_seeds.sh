#!/bin/bash
# Rebuilds the seed inputs cut from ../shared/data (make_seeds.cpp says which) into
# tests/fuzz/corpus/. Run by hand when a seed should change; the results are committed.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
data=${1:-$here/../../../shared/data}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
g++ -std=c++20 -O1 -w -o "$tmp/make_seeds" "$here/make_seeds.cpp" $(pkg-config --cflags --libs opencv4)
mkdir -p "$here/corpus/image" "$here/corpus/camera_frame" "$here/corpus/model"
"$tmp/make_seeds" "$data" "$here/corpus"
