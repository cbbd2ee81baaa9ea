#pragma once
// A run's stages against a baseline (the JSON of an earlier run): each stage's median divided by
// the run's calibration kernel and expressed at the baseline's, so a slower machine is not a
// regression. A stage slower than the threshold allows (and by over 0.5 ms: below, scheduling
// noise on a 2-core machine) is a regression, unless the run's contention explains it: `load`
// (the run's contention over the baseline's) is over `maxLoad` (on a busy machine a short stage
// waits whole time slices: 0.1 ms of projection read 8 ms beside six stress-ng workers on two
// cores), or the stage is slower by no more than `load` times what the threshold allows. Those
// are inconclusive. GPU stages (timer queries) are compared as measured.
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace lp::bench {

/// A stage median below this (ms) is too small to judge by percent.
inline constexpr double kMeasurableMs = 0.05;
/// A slowdown under this (ms) is within scheduling noise whatever its percentage.
inline constexpr double kNoiseMs = 0.5;

/// Parses a baseline's text (the whole of it: trailing text is an error). It must hold a positive
/// finite `calibration_ms` and, under `stages`, an object of stages each with a finite,
/// non-negative `median_ms`. Throws lp::Error naming `name` and the fault.
nlohmann::json parseBaseline(std::string_view text, const std::string& name);

struct Comparison {
  nlohmann::ordered_json regressions = nlohmann::ordered_json::array();
  nlohmann::ordered_json inconclusive = nlohmann::ordered_json::array();
  int compared = 0;                ///< stages compared
  std::vector<std::string> lines;  ///< one a stage: now against the baseline, as a report prints
};

/// `stages`: the run's (name, median ms), in order; `calibration`: its kernel's speed, ms.
Comparison compareWithBaseline(const std::vector<std::pair<std::string, double>>& stages,
                               double calibration, const nlohmann::json& baseline, double threshold,
                               double load, double maxLoad);

/// The GPU stages (name, median ms) against the baseline's "gpu" where both have a timer: as
/// measured (a GPU's time does not follow the CPU's kernel), the same threshold; into `c`.
void compareGpu(const std::vector<std::pair<std::string, double>>& gpu,
                const nlohmann::json& baseline, double threshold, Comparison& c);

enum class Verdict { NoRegression, Regression, Inconclusive };

/// The verdict and its line ("verdict: ...").
std::pair<Verdict, std::string> verdict(const Comparison& c, double threshold, double load);

}  // namespace lp::bench
