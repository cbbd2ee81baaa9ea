#include "liveprobe/bench/runs.h"

#include <cstdio>
#include <numeric>

#include "liveprobe/bench/calibration.h"
#include "liveprobe/bench/contention.h"
#include "liveprobe/capture/stages.h"
#include "text.h"

namespace lp::bench {

Runs measure(std::vector<std::string> stages, int repeat, int framesPerRun, const RunHooks& hooks) {
  Runs r;
  r.stages = std::move(stages);
  r.framesPerRun = framesPerRun;
  r.runMedians.resize(r.stages.size());
  CalibrationKernel kernel;
  const Contention contention;
  const auto stopped = [&] { return hooks.stop && hooks.stop(); };
  for (int run = 0; run < repeat && !stopped(); ++run) {
    for (int i = 0; i < 21; ++i) kernel.time();
    if (hooks.startRun) hooks.startRun(run);
    const std::size_t first = r.frames.size();
    for (int i = 0; i < framesPerRun && !stopped(); ++i) {
      kernel.time();
      r.frames.push_back(hooks.frame(run, i));
      r.frames.back().resize(r.stages.size());
      if (hooks.progress) hooks.progress(std::int64_t(r.frames.size()));
    }
    if (r.frames.size() == first) break;
    for (std::size_t s = 0; s < r.stages.size(); ++s) {
      std::vector<double> v;
      for (std::size_t f = first; f < r.frames.size(); ++f) v.push_back(r.frames[f][s]);
      r.runMedians[s].push_back(percentile(v, 0.5));
    }
  }
  r.stopped = stopped();
  r.calibrationMs = kernel.speed();
  r.contention = contention.factor();
  return r;
}

Summary summarize(const Runs& r, const std::string& description) {
  Summary out;
  const long runs = r.runMedians.empty() ? 0 : long(r.runMedians[0].size());
  out.lines.push_back(format("%-9s %9s %9s %9s %9s   (ms; %s of %s, %s)", "stage", "median", "p95",
                             "p99", "max", plural(runs, "run").c_str(),
                             plural(r.framesPerRun, "frame").c_str(), description.c_str()));
  nlohmann::ordered_json stages;
  for (std::size_t s = 0; s < r.stages.size(); ++s) {
    std::vector<double> v;
    for (const auto& f : r.frames) v.push_back(f[s]);
    const double med = percentile(r.runMedians[s], 0.5), p95 = percentile(v, 0.95),
                 p99 = percentile(v, 0.99), max = percentile(v, 1.0);
    stages[r.stages[s]] = {{"median_ms", med}, {"p95_ms", p95}, {"p99_ms", p99}, {"max_ms", max}};
    out.lines.push_back(
        format("%-9s %9.3f %9.3f %9.3f %9.3f", r.stages[s].c_str(), med, p95, p99, max));
  }
  out.json["stages"] = stages;
  std::vector<double> latency;
  for (const auto& f : r.frames)
    latency.push_back(f.empty() ? 0.0 : std::accumulate(f.begin() + 1, f.end(), 0.0));
  const double p50 = percentile(latency, 0.5), p95 = percentile(latency, 0.95),
               p99 = percentile(latency, 0.99);
  out.json["latency_ms"] = {{"p50", p50}, {"p95", p95}, {"p99", p99}};
  out.lines.push_back(
      format("latency (grab to shown) ms: p50 %.2f, p95 %.2f, p99 %.2f", p50, p95, p99));
  out.json["calibration_ms"] = r.calibrationMs;
  out.lines.push_back(format("calibration kernel: %.3f ms", r.calibrationMs));
  out.json["contention"] = r.contention;
  out.lines.push_back(
      format("contention: x%.2f (the run's threads waited for a CPU %.0f%% as long as they ran)",
             r.contention, 100 * (r.contention - 1)));
  return out;
}

}  // namespace lp::bench
