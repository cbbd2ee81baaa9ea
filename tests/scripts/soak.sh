#!/bin/bash
# Soak: replays FRAMES frames through the whole pipeline headless (with --coeffs-out and the HUD)
# and samples the process every 0.5 s from /proc. After warm-up (the first quarter of the
# samples) and before shutdown (the last sample may catch the process joining its threads and
# closing its files), the rest is split into two halves of equal time, A then B:
# - memory: a leak grows through the run, so B's peak resident memory exceeds A's by what B
#   leaked; the allocator's arenas (glibc's per-thread heaps, capped at two here: their number
#   otherwise follows how often threads contend, and a load that comes late in the run stepped
#   B's peak up by 12 MB in CI) grow while the threads first meet and then hold, so they move
#   A's peak, not B's over A's. B's peak may exceed A's by at most 4 MB plus twice FRAME_KB, a
#   decoded frame (a sample catches one to three frames alive: one decoded, one handed over,
#   one drawn; a busier machine late in the run moves that: 11.6 MB for a 1080p video, seen in
#   CI, and -9.7 MB here); 4,000 frames of a 1080p video: a leak of 12 kB a frame fails;
#   tests/scripts/soak_criterion.py tries the criterion. The growth from
#   warm-up to the end is printed, not bounded: on a loaded machine it is the arenas' (up to
#   +30 MB).
# - open file descriptors and threads must not grow: B's largest count is at most A's. (A looped
#   video reopens its decoder at each loop, so a sample may catch a moment with fewer.)
# Frames never queue: the handoff holds one frame. Live, the renderer takes the newest and each
# one it missed is counted as dropped, so a renderer that falls behind costs frames, not memory
# (the summary says how many); a headless replay's capture waits for the renderer instead.
# Usage: soak.sh LIVEPROBE FRAMES [SOURCE [FRAME_KB]]   (CI: 2000 and 4000 frames; README gives the
# 20,000 one). FRAME_KB: one decoded frame of SOURCE (default 0).
# A SOURCE under /dev/ is a camera (`live`); LIVEPROBE_PRELOAD then names a library to preload
# into liveprobe alone (the V4L2 emulator, configured by its LPEMU_* variables).
set -euo pipefail
liveprobe=$1 frames=$2 source=${3:-synthetic:128x64@1000} frame_kb=${4:-0}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
if [[ $source == /dev/* ]]; then
  run=(env ${LIVEPROBE_PRELOAD:+LD_PRELOAD=$LIVEPROBE_PRELOAD} "$liveprobe" live "$source"
       --view-size 64x36)
else
  run=("$liveprobe" replay "$source" --loop --size 64x36)
fi
# glibc's malloc arenas capped at two: their number otherwise follows how often threads meet on a
# busy machine (each new arena steps the resident memory up by megabytes, late in the run under a
# load that comes late), and a leak, not the machine's load, is what this run judges.
MALLOC_ARENA_MAX=2 "${run[@]}" --headless --frames "$frames" --msaa 1 --hud --quiet \
  --coeffs-out "$work/c.jsonl" > "$work/out.txt" 2>&1 &
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
printf '%s\n' "${samples[@]}" | awk -v n="$n" -v slack=$((4096 + 2 * frame_kb)) '
  NR > n / 4 && NR < n {
    if (!base) { base = $1; fd0 = $2; th0 = $3 }
    fds = fds " " $2; ths = ths " " $3
    if (NR < (n / 4 + n) / 2) { if ($1 > rA) rA = $1; if ($2 > fdA) fdA = $2; if ($3 > thA) thA = $3 }
    else { if ($1 > rB) rB = $1; if ($2 > fdB) fdB = $2; if ($3 > thB) thB = $3 } }
  END {
    top = rA > rB ? rA : rB
    printf "soak: %d samples; after warm-up RSS %d kB, peak %d kB in the first half and %d kB in the second (+%d kB), %d to %d kB in all; fds %d, threads %d\n",
           n, base, rA, rB, rB - rA, base, top, fd0, th0
    if (rB - rA > slack) { print "soak: resident memory grew by " rB - rA " kB from the first half to the second (more than " slack " kB): a leak"; exit 1 }
    if (fdB > fdA) { print "soak: the number of open file descriptors grew: " fds; exit 1 }
    if (thB > thA) { print "soak: the number of threads grew: " ths; exit 1 }
  }'
