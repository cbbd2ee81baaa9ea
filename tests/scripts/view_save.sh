#!/usr/bin/env bash
# Under xvfb-run: opens `liveprobe view` with the coefficients given, saves them with Ctrl+S
# (xdotool) and quits with Esc (tests/test_ux.cpp). $1: liveprobe, $2: the JSON to write,
# the rest: lighting options.
set -u
lp=$1 out=$2
shift 2
source "$(dirname "$0")/window_lib.sh"
wait_for_display || exit 1
"$lp" view --size 640x360 --msaa 1 --save-coeffs "$out" "$@" &
pid=$!
wait_for_window "$pid" || exit 1
sleep 1
xdotool windowfocus --sync "$wid"
xdotool key ctrl+s
sleep 1
xdotool key Escape
wait "$pid"
echo "rc: $?"
