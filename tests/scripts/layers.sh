#!/usr/bin/env bash
# The modules' dependencies go one way (docs/development.md): the SH core includes no GL, no
# OpenCV and nothing of capture; the frame (liveprobe::frame) knows only the SH core; HDR
# (liveprobe::hdr) knows frames and nothing of capture; the V4L2 device and the frame path
# (processed_frame.h, frame_processor.h) include nothing of HDR; what reads a frame's record
# (exchange) includes the frame it reads (liveprobe/capture/processed_frame.h), never the
# pipeline that makes it; the bench harness (liveprobe::bench) knows the SH core and the frame
# path's stages, no GL and nothing of the program. Each rule is a
# grep over the module's own sources; a line that breaks one is printed and fails the test.
# The GL context is a platform only: at most five calls besides its destructor, no void*.
set -euo pipefail
root=$1
status=0
forbid() {  # FOLDER PATTERN WHY
  local hits
  hits=$(grep -rnE "$2" "$root/$1" --include='*.h' --include='*.cpp' || true)
  if [[ -n $hits ]]; then
    echo "$1: $3:" >&2
    echo "$hits" >&2
    status=1
  fi
}
forbid shading/sh '#include [<"](GL/|glad/|EGL/|GLFW/|opencv2/|liveprobe/(capture|gl|exchange)/)' \
  'the SH core knows no GL, no OpenCV and no capture'
forbid frame '#include [<"](GL/|glad/|EGL/|GLFW/|opencv2/|liveprobe/(capture|hdr|gl|exchange)/)' \
  'the frame knows the SH core only'
forbid hdr '#include [<"]liveprobe/(capture|gl|exchange)/' 'HDR knows frames, not capture'
for f in capture/src/v4l2.cpp capture/src/v4l2_device.h capture/src/uvc_metadata.cpp \
  capture/src/uvc_metadata.h capture/include/liveprobe/capture/v4l2.h \
  capture/include/liveprobe/capture/processed_frame.h \
  capture/include/liveprobe/capture/frame_processor.h; do
  forbid "$f" '#include [<"]liveprobe/hdr/' 'the V4L2 device and the frame path include nothing of HDR'
done
forbid exchange '#include "liveprobe/capture/pipeline\.h"' \
  'exchange reads frames (processed_frame.h), not the pipeline'
forbid capture '#include "liveprobe/(gl|exchange)/' 'capture knows no GL and no exchange'
forbid bench '#include [<"](GL/|glad/|EGL/|GLFW/|opencv2/|liveprobe/(gl|exchange|hdr)/)' \
  'the bench harness knows the SH core and the frame path'"'"'s stages, no GL'
app=$(cd "$root/app/src" && ls *.h | sed 's/\./\\./' | paste -sd'|')
forbid bench "#include \"($app)\"" 'the bench harness includes nothing of the program'

ctx=$root/shading/gl/include/liveprobe/gl/context.h
body=$(sed -n '/^class GlContext {/,/^};/p' "$ctx")
calls=$(grep -cE '^ *virtual [^~]' <<< "$body" || true)
if [[ -z $body || $calls -gt 5 ]]; then
  echo "shading/gl: GlContext has $calls calls besides its destructor (at most 5):" >&2
  grep -nE '^ *virtual [^~]' <<< "$body" >&2 || true
  status=1
fi
if grep -nE 'void ?\*' <<< "$body" >&2; then
  echo "shading/gl: GlContext hands out a void* (above)" >&2
  status=1
fi
exit $status
