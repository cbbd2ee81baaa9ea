// libFuzzer target: image files through liveprobe's reader (libpng for PNG, a Radiance header
// check, then OpenCV for HDR, EXR, JPEG), under a pixel limit of 2^20. The first byte picks the
// extension. Any input ends in a frame within the limit with finite pixels, or in lp::Error.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "liveprobe/capture/image.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/sh/error.h"
#include "temp_input.h"

namespace {
constexpr std::int64_t kLimit = std::int64_t(1) << 20;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  lp::setMaxImagePixels(kLimit);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kExt[] = {".hdr", ".png", ".exr", ".jpg"};
  const std::string path = writeFuzzInput("image", kExt[data[0] % 4], data + 1, size - 1);
  try {
    lp::Frame f;
    lp::readImageFrame(path, f);
    if (std::int64_t(f.width) * f.height > kLimit || f.width <= 0 || f.height <= 0) std::abort();
    for (float v : f.rgb)
      if (!std::isfinite(v)) std::abort();
  } catch (const lp::Error&) {
  }
  std::remove(path.c_str());
  return 0;
}
