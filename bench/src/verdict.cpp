#include "liveprobe/bench/verdict.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "liveprobe/sh/error.h"
#include "text.h"

namespace lp::bench {

namespace {

nlohmann::ordered_json change(const std::string& stage, double pct, double ms, double median,
                              double base) {
  return {{"stage", stage},
          {"change_pct", pct},
          {"change_ms", ms},
          {"median_ms", median},
          {"baseline_median_ms", base}};
}

std::string listChanges(const nlohmann::ordered_json& stages) {
  std::string text;
  for (const auto& r : stages)
    text += format("%s%s +%.2f ms (%+.1f%%)", text.empty() ? "" : ", ",
                   r["stage"].get<std::string>().c_str(), r["change_ms"].get<double>(),
                   r["change_pct"].get<double>());
  return text;
}

}  // namespace

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

Comparison compareWithBaseline(const std::vector<std::pair<std::string, double>>& stages,
                               double calibration, const nlohmann::json& baseline, double threshold,
                               double load, double maxLoad) {
  Comparison c;
  const double baseCal = baseline.at("calibration_ms").get<double>();
  const nlohmann::json& baseStages = baseline.at("stages");
  for (const auto& [name, nowMs] : stages) {
    if (!baseStages.contains(name)) continue;
    const double baseMs = baseStages.at(name).at("median_ms").get<double>();
    const double nowAtBase = nowMs / calibration * baseCal;
    ++c.compared;
    if (baseMs < kMeasurableMs && nowAtBase < kMeasurableMs) {
      c.lines.push_back(format("%-9s %8.3f ms vs %.3f ms (too small to measure)", name.c_str(),
                               nowAtBase, baseMs));
      continue;
    }
    const double pct = baseMs > kMeasurableMs ? 100.0 * (nowAtBase - baseMs) / baseMs : 0.0;
    c.lines.push_back(baseMs > kMeasurableMs
                          ? format("%-9s %8.3f ms vs %.3f ms  %+7.1f%% (normalised by calibration)",
                                   name.c_str(), nowAtBase, baseMs, pct)
                          : format("%-9s %8.3f ms vs %.3f ms (baseline too small for a percentage)",
                                   name.c_str(), nowAtBase, baseMs));
    if (nowAtBase - baseMs > kNoiseMs && (baseMs <= kMeasurableMs || pct > threshold)) {
      const bool explained =
          load > maxLoad || (load > 1.0 && nowAtBase <= std::max(baseMs, kMeasurableMs) * load *
                                                            (1 + threshold / 100));
      (explained ? c.inconclusive : c.regressions)
          .push_back(change(name, pct, nowAtBase - baseMs, nowMs, baseMs));
    }
  }
  return c;
}

void compareGpu(const std::vector<std::pair<std::string, double>>& gpu,
                const nlohmann::json& baseline, double threshold, Comparison& c) {
  if (gpu.empty() || !baseline.contains("gpu") || !baseline["gpu"].value("timer", false)) return;
  for (const auto& [name, now] : gpu) {
    if (!baseline["gpu"].contains(name)) continue;
    const double base = baseline["gpu"][name]["median_ms"].get<double>();
    const double pct = base > 0 ? 100.0 * (now - base) / base : 0.0;
    ++c.compared;
    c.lines.push_back(
        format("%-11s %8.3f ms vs %.3f ms  %+7.1f%% (GPU time)", name.c_str(), now, base, pct));
    if (now - base > kNoiseMs && pct > threshold)
      c.regressions.push_back(change(name, pct, now - base, now, base));
  }
}

std::pair<Verdict, std::string> verdict(const Comparison& c, double threshold, double load) {
  if (!c.regressions.empty())
    return {Verdict::Regression, format("verdict: REGRESSION: %s (threshold %.0f%% and 0.5 ms)",
                                        listChanges(c.regressions).c_str(), threshold)};
  if (!c.inconclusive.empty())
    return {Verdict::Inconclusive,
            "verdict: inconclusive: slower than the threshold (" + format("%.0f", threshold) +
                "%) allows: " + listChanges(c.inconclusive) + "; but the run waited for a CPU x" +
                format("%.2f", load) +
                " as much as the baseline's did: run it again with nothing else running"};
  return {Verdict::NoRegression, format("verdict: no regression (%d stages within %.0f%% of the "
                                        "baseline)",
                                        c.compared, threshold)};
}

}  // namespace lp::bench
