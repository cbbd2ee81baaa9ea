// libFuzzer target: the bench baseline reader (`bench --baseline FILE`). Any input ends in a
// baseline whose calibration and stage medians are usable numbers, or in lp::Error.
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "liveprobe/bench/verdict.h"
#include "liveprobe/sh/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const nlohmann::json b =
        lp::bench::parseBaseline({reinterpret_cast<const char*>(data), size}, "fuzz.json");
    const double cal = b.at("calibration_ms").get<double>();
    if (!(cal > 0) || !std::isfinite(cal)) std::abort();
    for (const auto& [name, st] : b.at("stages").items()) {
      const double ms = st.at("median_ms").get<double>();
      if (!(ms >= 0) || !std::isfinite(ms)) std::abort();
    }
  } catch (const lp::Error&) {
  }
  return 0;
}
