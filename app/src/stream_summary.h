#pragma once
// What a stream's render loop measures, and the summary it prints at the end.
#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "hud.h"
#include "liveprobe/capture/pipeline.h"
#include "liveprobe/capture/processed_frame.h"
#include "liveprobe/capture/stages.h"
#include "stream_sinks.h"

namespace lp::cli {

struct StreamTally {
  std::array<std::vector<double>, kStageCount> stages;  ///< ms per drawn frame, by lp::Stage
  std::vector<double> latency;                          ///< capture to shown, ms
  std::size_t drawn = 0, saturated = 0;
  std::size_t withLight = 0, clippedLight = 0;  ///< frames with a light; of them, clipped
  std::vector<double> confidence;               ///< each frame's
  std::size_t brightestMeasured = 0;            ///< frames whose brightest pixel was measured
  /// The GPU's times of the drawn frames, where read, in GpuTimes::kTimes's order.
  std::array<std::vector<double>, GpuTimes::kTimes.size()> gpu;
  /// The source's frame number and timestamp (s) of the first and the last frame drawn: the rate
  /// it delivered at, lost frames included.
  std::uint64_t firstSequence = 0, lastSequence = 0;
  double firstTimestamp = 0, lastTimestamp = 0;

  /// Frames per second the source delivered between the first and the last frame drawn; 0 over
  /// less than `minSeconds`.
  double deliveredFps(double minSeconds) const;

  std::size_t frames() const { return latency.size(); }
  double median(Stage s) const;
};

/// A drawn frame into the tally and, where there is one, the HUD (with the pipeline's counters
/// and the sinks' lines).
void recordSample(StreamTally& t, const ProcessedFrame& f, double uploadMs, double renderMs,
                  double latencyMs, Hud* hud, const PipelineStats& st, const RecordSinks& sinks,
                  const GpuTimes& gpu = {});

/// The run's GPU time: "GPU time (medians, timer queries): gpu_upload 0.05 ms, ..." where there
/// were readings, else "GPU time: no GPU timer (GL)" where `gl` is a software rasterizer or its
/// timer read nothing.
std::string gpuTimeLine(const StreamTally& t, const std::string& gl);

/// "grab 0.95, convert 0.00, ...": the median of each stage up to render (merge and resample
/// only where they ran).
std::string stageMedians(const StreamTally& t);

/// The run's summary on stderr: frames, stage medians, latency, lights, the sinks' lines,
/// confidence, shortened gaps and --smooth's lag.
void printSummary(const std::string& description, const PipelineStats& st, const StreamTally& t,
                  double smoothSeconds, bool interrupted, const RecordSinks& sinks);

/// After a camera's run, what a user can do about what it measured, one line each, where it
/// applies: a clipped light without --bracket; a bracket whose exposures disagree with each
/// other (a response that is not the camera's); a bracket that never measured its brightest
/// light (the control's limit: neutral density). `bracketed`: the run merged a bracket.
void printCameraHints(const StreamTally& t, const PipelineStats& st, bool bracketed,
                      double modeFps);

}  // namespace lp::cli
