// libFuzzer target: a camera response file (`calibrate --out`, read by `--response`). Any input
// ends in a response whose three curves rise with the code and are finite and non-negative, or in
// lp::Error.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "liveprobe/hdr/merge.h"
#include "liveprobe/sh/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const lp::CameraResponse r =
        lp::CameraResponse::parse(std::string(reinterpret_cast<const char*>(data), size), "fuzz");
    if (r.firstDecrease() >= 0) std::abort();
    for (const auto& curve : r.linear)
      for (float v : curve)
        if (!std::isfinite(v) || v < 0) std::abort();
  } catch (const lp::Error&) {
  }
  return 0;
}
