// libFuzzer target: a recording's sidecar (FILE.json beside a video), as `replay` reads it. Any
// input ends in a sidecar with finite, positive scales and finite timestamps, or in lp::Error.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "liveprobe/capture/recorder.h"
#include "liveprobe/sh/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const lp::RecordingSidecar s =
        lp::parseRecordingSidecar({reinterpret_cast<const char*>(data), size}, "fuzz.mkv.json");
    auto good = [](double x) { return std::isfinite(x) && x > 0; };
    if (!good(s.scale)) std::abort();
    for (double v : s.scales)
      if (!good(v)) std::abort();
    for (double t : s.stamps)
      if (!std::isfinite(t)) std::abort();
  } catch (const lp::Error&) {
  }
  return 0;
}
