#pragma once
// GPU time of the frame's GL work (upload, projection, render) by timer queries, read a few
// frames late so that reading never waits for the GPU (as Magnum's FrameProfilerGL does).
// A software rasterizer has no GPU timer (llvmpipe answers GL_TIME_ELAPSED with 0 or a few
// nanoseconds): hasTimer() is false there, and false once a few finished queries have all said 0
// anywhere; the callers then say "no GPU timer" rather than 0 ms.
#include <array>
#include <cstdint>
#include <optional>

#include "liveprobe/gl/gl.h"

namespace lp::gl {

class GpuTimer {
 public:
  /// Stages timed, one query each per frame in flight.
  enum Stage : std::uint8_t { Upload, Project, Merge, Render, kStages };
  static constexpr const char* kNames[kStages] = {"gpu_upload", "gpu_project", "gpu_merge",
                                                  "gpu_render"};
  /// Frames in flight: a result is read this many frames after it was asked for.
  static constexpr int kLatency = 3;

  GpuTimer();
  ~GpuTimer();
  GpuTimer(const GpuTimer&) = delete;
  GpuTimer& operator=(const GpuTimer&) = delete;

  /// Starts a frame: reads what finished of the frame kLatency frames ago.
  void beginFrame();
  /// One stage's GL commands between begin() and end() (queries do not nest: one at a time).
  void begin(Stage stage);
  void end();

  /// The latest measured milliseconds of a stage; nullopt before any, or without a GPU timer.
  std::optional<double> ms(Stage stage) const;
  /// The milliseconds of a stage read by the last beginFrame() (a frame kLatency frames back);
  /// nullopt where that frame did not time it, it was not finished, or there is no GPU timer.
  std::optional<double> justRead(Stage stage) const;
  /// False where the context's timer answers 0 to every query (llvmpipe).
  bool hasTimer() const { return hasTimer_; }

 private:
  std::array<std::array<GLuint, kStages>, kLatency + 1> queries_{};
  std::array<std::array<bool, kStages>, kLatency + 1> asked_{};
  std::array<std::optional<double>, kStages> latest_{}, justRead_{};
  int frame_ = -1;
  int answered_ = 0, nonZero_ = 0;
  bool hasTimer_ = true, open_ = false;
};

}  // namespace lp::gl
