#pragma once
// A bench's runs and what they measured: `repeat` runs of N frames, every frame's time by stage,
// the calibration kernel timed throughout (21 repetitions before each run, one before each frame)
// and the contention over all of it; then the report's figures.
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace lp::bench {

struct Runs {
  std::vector<std::string> stages;              ///< names, in the frame's order
  std::vector<std::vector<double>> frames;      ///< every frame of every run in order, ms by stage
  std::vector<std::vector<double>> runMedians;  ///< by stage: each run's median
  int framesPerRun = 0;
  double calibrationMs = 0;  ///< the calibration kernel's fastest repetition
  double contention = 1;     ///< Contention::factor over the runs
  bool stopped = false;      ///< `stop` ended them early
};

struct RunHooks {
  std::function<void(int run)> startRun;                         ///< before a run's first frame
  std::function<std::vector<double>(int run, int frame)> frame;  ///< one frame, ms by stage
  std::function<bool()> stop;                                    ///< polled between frames
  std::function<void(std::int64_t framesDone)> progress;
};

/// Runs them. A run that timed no frame (stopped before its first) adds no median.
Runs measure(std::vector<std::string> stages, int repeat, int framesPerRun, const RunHooks& hooks);

struct Summary {
  /// "stages" (per stage: median_ms, the median of the runs' medians; p95_ms, p99_ms and max_ms
  /// over every frame), "latency_ms" (p50, p95, p99 of each frame's stages after the first: from
  /// the grab to the frame shown), "calibration_ms", "contention".
  nlohmann::ordered_json json;
  std::vector<std::string> lines;  ///< the table and the figures, as a report prints them
};

/// `description`: the source, for the table's heading.
Summary summarize(const Runs& runs, const std::string& description);

}  // namespace lp::bench
