// libFuzzer target: a recording's sidecar (FILE.json beside a video, FRAME.png.json beside a
// bracket's numbered frames), as `replay` reads it. Any input ends in a sidecar with finite,
// positive scales, finite timestamps, a bracket of 0 to 5 frames with every frame's exposure
// and, where a bracket carries its camera response, a response the merge can use (three rising,
// finite, non-negative curves), or in lp::Error.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "liveprobe/capture/recorder.h"
#include "liveprobe/hdr/merge.h"
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
    if (s.bracket < 0 || s.bracket > 5) std::abort();
    if (s.bracket > 0 && s.scales.size() != s.stamps.size()) std::abort();
    if (!s.response.empty()) {  // replay decodes the bracket with it
      const lp::CameraResponse r = lp::CameraResponse::parse(s.response, "fuzz.mkv.json: response");
      if (r.firstDecrease() >= 0) std::abort();
      for (const auto& curve : r.linear)
        for (float v : curve)
          if (!std::isfinite(v) || v < 0) std::abort();
    }
  } catch (const lp::Error&) {
  }
  return 0;
}
