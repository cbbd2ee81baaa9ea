#!/usr/bin/env bash
# Drives a real liveprobe window with xdotool, under xvfb-run (tests/test_window.cpp). Prints one
# "key: value" line per observation. $1: the liveprobe binary, $2: a folder for the screenshots.
set -u
lp=$1 out=$2
source "$(dirname "$0")/window_lib.sh"
wait_for_display || exit 1
"$lp" replay synthetic:256x128@30 --size 960x540 --msaa 1 >"$out/log" 2>&1 &
pid=$!
wait_for_window "$pid" || exit 1
# The title is updated about once a second, after a frame is drawn: wait for what it says.
title_until() {  # $1: a pattern the title must match (grep -E), within 45 s of wall time
  local t= deadline=$((SECONDS + 45))
  while ((SECONDS < deadline)); do
    t=$(xdotool getwindowname "$wid")
    grep -qE "$1" <<<"$t" && break
    sleep 0.1
  done
  echo "$t"
}
title_until 'frames/s$' >/dev/null
sleep 1
xdotool windowfocus --sync "$wid"
xdotool key space  # pause
title_until 'paused$' >/dev/null
sleep 1.5
echo "paused_a: $(title_until 'paused$')"
xwd -root -silent >"$out/hud.xwd"
xdotool key h  # hide the HUD: the same paused frame without it
sleep 1.5
xwd -root -silent >"$out/nohud.xwd"
echo "paused_b: $(title_until 'paused$')"
# Exposure keys, paused and without the HUD: '=', shifted '=' ('+') and keypad '+' are each one
# half-stop step ('-' takes it back), so the three screenshots after them are the same.
for k in equal plus KP_Add; do
  xdotool key "$k"
  sleep 2
  xwd -root -silent >"$out/exposure_$k.xwd"
  xdotool key minus
  sleep 1
done
xdotool key h space  # HUD back, resume
title_until 'frames/s$' >/dev/null
sleep 2
echo "resumed: $(title_until 'frames/s$')"
t0=$(date +%s%N)
xdotool key Escape  # one short tap
wait "$pid"
rc=$?
t1=$(date +%s%N)
echo "quit_ms: $(((t1 - t0) / 1000000))"
echo "rc: $rc"
