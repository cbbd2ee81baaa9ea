#pragma once
// One frame of `liveprobe bench`, timed stage by stage through the frame path and the headless
// viewer as a replay takes it: the stages bench times, the scene it draws into, what a run keeps
// from frame to frame, and the GPU's own time per stage (timer queries). The harness around it
// (the calibration kernel, the runs, the comparison and the plot) is liveprobe::bench.
#include <array>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "gpu_projection.h"
#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/photometry.h"
#include "liveprobe/capture/stages.h"
#include "liveprobe/gl/gpu_timer.h"
#include "liveprobe/sh/executor.h"
#include "viewer.h"

namespace lp::cli {

// The stages bench times, in the profiler's order (bench merges no bracket); the arrays below are
// indexed by position in this list.
inline constexpr std::array kBenchStages = {Stage::Grab,     Stage::Convert, Stage::Project,
                                            Stage::Resample, Stage::Upload,  Stage::Render,
                                            Stage::Readback};
inline constexpr int kBenchStageCount = int(kBenchStages.size());
/// A stage's name (the names are literals: NUL-terminated).
inline const char* benchStageName(int s) { return stageName(kBenchStages[std::size_t(s)]).data(); }

using BenchTimes = std::array<double, kBenchStageCount>;  ///< ms, by position in kBenchStages

/// What the bench draws into, made once for every run.
struct BenchScene {
  Viewer viewer;  ///< headless: the context, the renderer with the model, the one draw
  LayoutSpec layout;
  glm::mat3 orientation;
  BenchTimes inject{};         ///< busy work added to each stage, ms (proves the detector works)
  bool gpuProjection = false;  ///< as decided for the context that came up
  Photometry photometry;       // as the pipeline: one lookup table, each frame's exposure scales it
  /// GPU time of the upload, the projection and the render, by timer queries read three frames
  /// late: every frame's, by stage, as they came back.
  std::unique_ptr<gl::GpuTimer> timer;
  std::array<std::vector<double>, gl::GpuTimer::kStages> gpuTimes;
};

/// What one run keeps from frame to frame.
struct RunState {
  explicit RunState(const BenchScene& scene)
      : processor({scene.layout, scene.photometry, scene.orientation, 1, {.maxLights = 0}}) {}
  std::shared_ptr<Frame> frame = std::make_shared<Frame>();   ///< the background shares it
  std::shared_ptr<Image> linear = std::make_shared<Image>();  ///< its linear copy, reused
  FrameProcessor processor;    ///< the frame path every command shares
  float exposure = 1.0f;       ///< from the first frame's irradiance
  Sh9 last;                    ///< the last frame's coefficients (in the report)
  gl::GpuFrameProjection gpu;  ///< the projection on the GPU (where the scene projects there)
};

/// One frame through the pipeline, stage by stage, as the replay pipeline does it: grab, then
/// the frame path (FrameProcessor::run: convert, only where the display cannot take the frame as
/// it is; project, on the CPU or the GPU; resample, for a layout GL does not draw as it is), then
/// upload, render and read back. One StageClock times them all.
BenchTimes timeFrame(BenchScene& scene, RunState& run, FrameSource& source,
                     const std::string& sourceName, Executor& pool, bool first);

/// The GPU's time per stage (timer queries): medians over every frame that came back, printed
/// and returned; {"timer": false} where the context has no GPU timer (a software rasterizer).
nlohmann::ordered_json gpuSummary(const BenchScene& scene);

}  // namespace lp::cli
