#!/usr/bin/env bash
# Drives a real liveprobe window with xdotool, under xvfb-run (tests/test_ux.cpp). Prints one
# "key: value" line per observation. $1: the liveprobe binary, $2: a folder for the screenshots.
set -u
lp=$1 out=$2
"$lp" replay synthetic:256x128@30 --size 960x540 --msaa 1 >"$out/log" 2>&1 &
pid=$!
wid=
for _ in $(seq 200); do
  wid=$(xdotool search --name '^liveprobe' 2>/dev/null | head -1)
  [[ -n $wid ]] && break
  sleep 0.1
done
echo "window: ${wid:-none}"
[[ -z $wid ]] && { kill "$pid"; exit 1; }
sleep 2  # a few frames drawn, the title updated
xdotool windowfocus --sync "$wid"
xdotool key space  # pause
sleep 1.5
echo "paused_a: $(xdotool getwindowname "$wid")"
xwd -root -silent >"$out/hud.xwd"
xdotool key h  # hide the HUD: the same paused frame without it
sleep 1
xwd -root -silent >"$out/nohud.xwd"
echo "paused_b: $(xdotool getwindowname "$wid")"
xdotool key h space  # HUD back, resume
sleep 2
echo "resumed: $(xdotool getwindowname "$wid")"
t0=$(date +%s%N)
xdotool key Escape  # one short tap
wait "$pid"
rc=$?
t1=$(date +%s%N)
echo "quit_ms: $(((t1 - t0) / 1000000))"
echo "rc: $rc"
