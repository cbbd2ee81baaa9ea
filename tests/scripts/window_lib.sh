# Sourced by the xdotool sessions: wait_for_display returns once the X server answers (xvfb-run
# starts the session when Xvfb says it is ready; on a machine whose cores are all busy a client
# has still been refused), wait_for_window PID sets $wid to the liveprobe window. The deadlines
# (60 s of wall time) are for a machine whose cores are all busy, not an idle one's.
wait_for_display() {
  local deadline=$((SECONDS + 60))
  while ((SECONDS < deadline)); do
    xdotool getdisplaygeometry >/dev/null 2>&1 && return 0
    sleep 0.2
  done
  echo "no display: the X server at $DISPLAY never answered"
  return 1
}

wait_for_window() {
  wid=
  local deadline=$((SECONDS + 60))
  while ((SECONDS < deadline)); do
    wid=$(xdotool search --name '^liveprobe' 2>/dev/null | head -1)
    [[ -n $wid ]] && return 0
    sleep 0.1
  done
  kill "$1"
  echo "no window"
  return 1
}
