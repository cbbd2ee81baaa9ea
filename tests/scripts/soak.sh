#!/bin/bash
# Soak: replays FRAMES frames through the whole pipeline headless (with --coeffs-out and the HUD)
# and samples the process every 0.5 s from /proc: after warm-up (the first quarter of the samples)
# and before shutdown (the last sample may catch the process joining its threads and closing its
# files), resident memory must stay within a tolerance, and open file descriptors and threads must
# not grow: the second half's largest count is at most the first half's. (A looped video reopens
# its decoder at each loop, so a sample may catch a moment with fewer threads or files.)
# Usage: soak.sh LIVEPROBE FRAMES [SOURCE]   (CI: 2000 frames; README gives the 20,000 one)
# A SOURCE under /dev/ is a camera (`live`); LIVEPROBE_PRELOAD then names a library to preload
# into liveprobe alone (the V4L2 emulator, configured by its LPEMU_* variables).
set -euo pipefail
liveprobe=$1 frames=$2 source=${3:-synthetic:128x64@1000}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
if [[ $source == /dev/* ]]; then
  run=(env ${LIVEPROBE_PRELOAD:+LD_PRELOAD=$LIVEPROBE_PRELOAD} "$liveprobe" live "$source"
       --view-size 64x36)
else
  run=("$liveprobe" replay "$source" --loop --size 64x36)
fi
"${run[@]}" --headless --frames "$frames" --msaa 1 --hud --quiet --coeffs-out "$work/c.jsonl" \
  > "$work/out.txt" 2>&1 &
pid=$!
samples=()
while kill -0 "$pid" 2>/dev/null; do
  if [ -r "/proc/$pid/status" ]; then
    rss=$(awk '/^VmRSS:/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
    threads=$(awk '/^Threads:/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
    fds=$(ls "/proc/$pid/fd" 2>/dev/null | wc -l || true)
    [ -n "$rss" ] && [ -n "$threads" ] && samples+=("$rss $fds $threads")
  fi
  sleep 0.5
done
wait "$pid" || { echo "soak: liveprobe failed:"; cat "$work/out.txt"; exit 1; }
cat "$work/out.txt"  # the summary: frames captured, drawn, dropped and skipped
lines=$(wc -l < "$work/c.jsonl")
[ "$lines" -eq "$frames" ] || { echo "soak: $lines coefficient lines, expected $frames"; exit 1; }
n=${#samples[@]}
[ "$n" -ge 8 ] || { echo "soak: only $n samples; the run was too short to judge"; exit 1; }
printf '%s\n' "${samples[@]}" | awk -v n="$n" '
  NR > n / 4 && NR < n { if (!base) { base = $1; fd0 = $2; th0 = $3 }
               fds = fds " " $2; ths = ths " " $3
               if ($1 > rmax) rmax = $1
               if (NR < (n / 4 + n) / 2) { if ($2 > fdA) fdA = $2; if ($3 > thA) thA = $3 }
               else { if ($2 > fdB) fdB = $2; if ($3 > thB) thB = $3 } }
  END {
    growth = rmax - base
    fdbad = fdB > fdA; thbad = thB > thA
    printf "soak: %d samples; after warm-up RSS %d -> max %d kB (+%d), fds %d, threads %d\n",
           n, base, rmax, growth, fd0, th0
    # Tolerance: 8 MB or 10%, whichever is larger (allocator noise, glibc arenas).
    tol = base / 10; if (tol < 8192) tol = 8192
    if (growth > tol) { print "soak: resident memory grew by " growth " kB"; exit 1 }
    if (fdbad) { print "soak: the number of open file descriptors grew: " fds; exit 1 }
    if (thbad) { print "soak: the number of threads grew: " ths; exit 1 }
  }'
