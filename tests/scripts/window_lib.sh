# Sourced by the xdotool sessions: wait_for_window PID sets $wid to the liveprobe window (20 s).
wait_for_window() {
  wid=
  for _ in $(seq 200); do
    wid=$(xdotool search --name '^liveprobe' 2>/dev/null | head -1)
    [[ -n $wid ]] && return 0
    sleep 0.1
  done
  kill "$1"
  echo "no window"
  return 1
}
