# Sourced by the xdotool sessions: wait_for_window PID sets $wid to the liveprobe window. The
# deadline (60 s of wall time) is for a machine whose cores are all busy, not an idle one's.
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
