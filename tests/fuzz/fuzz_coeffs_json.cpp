// libFuzzer target: the coefficient JSON reader (what `render --coeffs` and `view --coeffs`
// read). Any input must end in coefficients or in lp::Error / a JSON parse error; never a crash,
// undefined behaviour or a non-finite coefficient. Built by scripts/fuzz (clang-14); the corpus
// (tests/fuzz/corpus/coeffs_json) is also replayed by the normal suite (Fuzz.*CorpusReplays).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "liveprobe/exchange/coeffs_io.h"
#include "liveprobe/sh/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const nlohmann::json j = nlohmann::json::parse(data, data + size);
    const lp::Sh9 sh = lp::coefficientsFromJson(j, "fuzz");
    if (!lp::isFinite(sh)) std::abort();  // the reader promises finite coefficients
    for (const lp::Light& l : lp::lightsFromJson(j, "fuzz"))  // and finite, unit lights
      if (!std::isfinite(l.power.x) || !std::isfinite(l.power.y) || !std::isfinite(l.power.z) ||
          std::abs(glm::length(l.dir) - 1.0f) > 1e-3f)
        std::abort();
  } catch (const nlohmann::json::exception&) {
  } catch (const lp::Error&) {
  }
  return 0;
}
