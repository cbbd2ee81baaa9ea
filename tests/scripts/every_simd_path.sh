#!/bin/bash
# Runs the SH core's accuracy tests once per SIMD path this CPU runs, each forced with
# LIVEPROBE_SIMD (liveprobe --version lists the paths), but the one chosen without it: the suite
# itself runs these tests on that one. Usage: every_simd_path.sh TESTS LIVEPROBE
set -euo pipefail
tests=$1 liveprobe=$2
# The suites whose numbers come from the projection kernels (each compares with an analytic
# case, a float64 sum, the brute-force integral or R&H's published table).
filter='ShCore.*:Layout.*:EveryLayout.*:CubeFaces.*:Published.*:Accuracy.*:ShRotation.*:Handoff.*:Simd.*'
version=$("$liveprobe" --version)
paths=$(sed -n 's/^simd: .*(this CPU runs: \(.*\))$/\1/p' <<<"$version")
chosen=$(sed -n 's/^simd: \([a-z0-9]*\) .*/\1/p' <<<"$version")
if [ -z "$paths" ] || [ -z "$chosen" ]; then
  echo "every_simd_path: '$liveprobe --version' lists no SIMD paths" >&2
  exit 1
fi
others=
for p in $paths; do [ "$p" = "$chosen" ] || others+=" $p"; done
echo "every_simd_path: $chosen is the suite's own path; forcing the others:${others:- none}"
for p in $others; do
  echo "== LIVEPROBE_SIMD=$p"
  LIVEPROBE_SIMD=$p "$tests" --gtest_filter="$filter" --gtest_brief=1
done
echo "every_simd_path: accuracy tests passed on:$others (and $chosen in the suite)"
