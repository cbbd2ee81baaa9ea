// libFuzzer target: one buffer of a UVC camera's metadata node (uvc_meta_buf blocks with their
// payload headers), as bracketing reads each frame's exposure time from it. Any input ends in no
// exposure or a positive, finite one.
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "liveprobe/capture/v4l2.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto t = lp::parseUvcExposure(data, size);
  if (t && !(std::isfinite(*t) && *t > 0)) std::abort();
  return 0;
}
