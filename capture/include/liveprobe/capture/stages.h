#pragma once
// The stages of a frame's path, named and ordered once: capture's (grab, merge, convert, project,
// resample, on the capture thread) then the viewer's (upload, render, readback). Every report of
// where a frame's time went (the per-frame records, the HUD's plot, the summary, `liveprobe bench`)
// reads its stages from here.
#include <array>
#include <chrono>
#include <cstddef>
#include <string_view>
#include <vector>

namespace lp {

enum class Stage : int {
  Grab,      ///< the source's next frame, decoded
  Merge,     ///< an exposure bracket's merge into radiance (with its projection, where one pass)
  Convert,   ///< the linear copy kept for display (8-bit frames are linearised in the projection)
  Project,   ///< coefficients and lights (none for a bracket projected as it merged)
  Resample,  ///< the display's equirect of a layout GL does not draw as it is (cube, ball, fisheye)
  Upload,    ///< lighting and background handed to GL
  Render,    ///< the model drawn (and the HUD)
  Readback,  ///< the frame read back (headless outputs, bench)
  Count
};

inline constexpr std::size_t kStageCount = std::size_t(Stage::Count);

inline constexpr std::array<std::string_view, kStageCount> kStageNames = {
    "grab", "merge", "convert", "project", "resample", "upload", "render", "readback"};

/// A stage that runs for some sources only (a bracket's merge, a layout's resample): reports show
/// it where it ran.
constexpr bool stageRunsForSomeSources(Stage s) {
  return s == Stage::Merge || s == Stage::Resample;
}

constexpr std::string_view stageName(Stage s) { return kStageNames[std::size_t(s)]; }

/// The stage called `name` (Stage::Count: none).
constexpr Stage stageNamed(std::string_view name) {
  for (std::size_t i = 0; i < kStageCount; ++i)
    if (kStageNames[i] == name) return Stage(i);
  return Stage::Count;
}

/// One frame's time per stage, ms (0: the stage did not run for it).
struct StageTimes {
  std::array<double, kStageCount> ms{};

  double& operator[](Stage s) { return ms[std::size_t(s)]; }
  double operator[](Stage s) const { return ms[std::size_t(s)]; }
  /// Adds `other`'s stages to these.
  StageTimes& operator+=(const StageTimes& other) {
    for (std::size_t i = 0; i < kStageCount; ++i) ms[i] += other.ms[i];
    return *this;
  }
};

/// The one stage timer of the frame path (FrameProcessor::run, the capture pipeline, bench): a
/// frame's work timed as laps on the steady clock, each lap's time added to its stage.
/// The p-quantile (0..1) of `v`, linear between the two nearest values; 0 for none.
double percentile(std::vector<double> v, double p);

class StageClock {
 public:
  using Clock = std::chrono::steady_clock;
  StageClock() : last_(Clock::now()) {}
  /// Starts the next lap now: what ran since the last lap goes to no stage.
  void skip() { last_ = Clock::now(); }
  /// The time since the last lap (or the clock's start, or skip()) goes to `s`; returns it, ms.
  double lap(Stage s) {
    const auto now = Clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last_).count();
    times[s] += ms;
    last_ = now;
    return ms;
  }
  StageTimes times;

 private:
  Clock::time_point last_;
};

}  // namespace lp
