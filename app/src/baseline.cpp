#include "baseline.h"

#include <cmath>

#include "liveprobe/sh/error.h"

namespace lp::cli {

nlohmann::json parseBaseline(std::string_view text, const std::string& name) {
  nlohmann::json b;
  try {
    b = nlohmann::json::parse(text);
    const double cal = b.at("calibration_ms").get<double>();
    if (!(cal > 0) || !std::isfinite(cal))
      throw Error(name + ": calibration_ms must be a positive number");
    const nlohmann::json& stages = b.at("stages");
    if (!stages.is_object()) throw Error(name + ": stages must be an object of stage names");
    for (const auto& [stage, st] : stages.items()) {
      const double ms = st.at("median_ms").get<double>();
      if (!(ms >= 0) || !std::isfinite(ms))
        throw Error(name + ": stage " + stage + ": median_ms must be a non-negative number");
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(name + ": not a liveprobe bench JSON (" + e.what() + ")");
  }
  return b;
}

}  // namespace lp::cli
