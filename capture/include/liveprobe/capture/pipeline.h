#pragma once
// The capture pipeline: a thread grabs, converts (photometry) and projects each frame, then
// hands the newest coefficients to the render loop through a latest-value slot. With
// Handoff::Latest capture never waits for rendering: a frame not taken before the next one is
// ready is dropped and counted. With Handoff::Every (offline output) capture waits until each
// frame is taken, so every frame is rendered.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "liveprobe/capture/ball.h"
#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/capture/photometry.h"
#include "liveprobe/capture/processed_frame.h"
#include "liveprobe/capture/stages.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/hdr/merge.h"
#include "liveprobe/sh/executor.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/projector.h"
#include "liveprobe/sh/sh.h"

namespace lp {

enum class Handoff : std::uint8_t { Latest, Every };

/// What the capture thread runs on its GPU (PipelineOptions::projectOnGpu).
struct GpuWork {
  /// The projection every frame takes (FrameRequest::projectWith).
  std::function<Sh9(const ProjectionJob&)> project;
  /// A bracket's pixel loop (BracketMerger::setFrameKernel): merged, and projected as it merges,
  /// on the GPU.
  merge::FrameKernel merge;
  bool mergeTurns = false;  ///< it turns the older frames itself (merge::FrameInput::turn)
  /// It keeps each merge's luminance, read back where the merger asks (merge::LuminanceFetch).
  merge::LuminanceFetch mergeLuminance;
  /// The GPU's time for the last merge (ms), where the context has a timer.
  std::function<std::optional<double>()> mergeMs;
  /// Where the display's context shares the merging one's objects: the last merge's frame, kept
  /// on the GPU (merge::FrameInput::rgbKept), handed over as the background (Background::onGpu)
  /// instead of read back.
  std::function<std::shared_ptr<const gl::GpuImage>()> mergedImage;
};

struct PipelineOptions {
  LayoutSpec layout;
  Photometry photometry;
  /// The environment's orientation (world from file; orthogonal, a reflection allowed), applied
  /// to the coefficients by lp::rotateSh. The display turns the background by the same matrix.
  std::optional<glm::mat3> rotation;
  double smoothSeconds = 0;     ///< EMA time constant on the 27 numbers; 0 = off
  bool loop = false;            ///< rewind at the end of the source
  std::int64_t maxFrames = -1;  ///< stop after this many frames; -1 = the whole source
  Handoff handoff = Handoff::Latest;
  bool realtime = false;   ///< pace capture by the source's timestamps
  bool keepImages = true;  ///< hand the linear frame over too (for the background)
  unsigned threads = 2;    ///< threads for one frame's projection
  int reduce = 1;          ///< equirect: project an f x f area average (reduceEquirect)
  /// Light extraction (liveprobe/sh/lights.h); maxLights = 0 (the default) leaves it off.
  LightOptions lights{.maxLights = 0};
  /// Exposure bracketing: each frame is merged with the ones before it into radiance
  /// (liveprobe/hdr/merge.h) before anything else sees it (onFrame sees each as it came).
  std::optional<MergeOptions> bracket;
  /// A frame whose confidence in what it measured (FrameConfidence::measured(): the unseen share
  /// aside) is below this keeps the last good frame's lighting (0: off).
  double holdBelow = 0;
  /// Called on the capture thread for every frame handed over (at its time where capture is
  /// paced), just before the handoff: as many calls as PipelineStats::captured.
  std::function<void(const ProcessedFrame&)> onCaptured;
  /// Called on the capture thread with every raw frame as the source gave it (for recording).
  std::function<void(const Frame&)> onFrame;
  /// Polled while capture waits (pacing, a pause): true ends capture within kStopPollSeconds,
  /// as stop() does. The app passes its signal flag (a signal handler cannot wake a waiter).
  std::function<bool()> interrupted;
  /// Paced at the source's time (`realtime`): a gap between two frames' timestamps beyond this many
  /// seconds (and beyond ten frame intervals) is not waited out; the frame comes one frame interval
  /// after the previous one (counted in PipelineStats::gapsShortened).
  double maxGapSeconds = 10.0;
  /// --circle auto in a stream: the mirror ball followed from frame to frame (BallFollower,
  /// liveprobe/capture/ball.h), the layout fitted again whenever its circle moves. `layoutFor`
  /// makes the layout of a circle (a calibrated camera's traced ball); `say` is told, once each,
  /// when the ball is found, lost and found again. Frames before the first find are not projected
  /// and not counted against maxFrames (PipelineStats::beforeBall); a frame the ball is lost in is
  /// projected through the last circle at confidence 0 and keeps the last good lighting (held,
  /// whatever holdBelow says).
  struct FollowBall {
    std::function<LayoutSpec(glm::vec3 circle)> layoutFor;
    std::function<void(const std::string&)> say;
    /// Where in a W x H frame the ball is searched for (BallFollower's searchWithin); none: the
    /// whole frame.
    std::function<std::optional<FrameWindow>(int width, int height)> searchWithin;
  };
  std::optional<FollowBall> followBall;
  /// Frames projected on the GPU (--projection): called on the capture thread as it starts (a GL
  /// context is current on one thread), it gives what runs on that thread's GPU (GpuWork),
  /// destroyed on the capture thread as it ends. None, or empty parts: the CPU.
  std::function<GpuWork()> projectOnGpu;
};

/// How often a waiting capture thread polls PipelineOptions::interrupted.
inline constexpr double kStopPollSeconds = 0.02;

struct PipelineStats {
  std::size_t captured = 0;        ///< frames processed
  std::size_t taken = 0;           ///< frames the consumer took
  std::size_t dropped = 0;         ///< frames replaced in the slot, or left in it at the stop,
                                   ///< before anyone took them: captured = taken + dropped
  std::size_t skipped = 0;         ///< frames the source could not decode
  std::size_t unidentified = 0;    ///< bracketed frames of an exposure not told (left out)
  std::string unidentifiedReport;  ///< those by stop and cause (FrameSource::unidentifiedReport)
  std::size_t gapsShortened = 0;   ///< timestamp gaps over PipelineOptions::maxGapSeconds
  std::size_t held = 0;            ///< frames that kept the last good lighting (holdBelow)
  /// Merged frames that tell whether a bracket's exposures agree (several merged, or one that
  /// contradicted the others), and of them those that disagreed on most of the power they kept
  /// (FrameConfidence::agreement under 0.5): a response other than the camera's does so.
  std::size_t mergesTelling = 0, mergesDisagreeing = 0;
  std::string endReason;             ///< why the source ended early, if it did
  std::size_t reconnects = 0;        ///< times the source reopened its stream (a network camera)
  std::size_t stale = 0;             ///< frames the source replaced before capture took them
  std::string error;                 ///< the fatal error that stopped capture, if any
  std::size_t beforeBall = 0;        ///< frames before the followed ball was found (FollowBall)
  std::size_t ballLost = 0;          ///< frames the followed ball was lost in
  std::size_t ballMoves = 0;         ///< times its circle moved (the layout fitted again)
  std::size_t projectedOnGpu = 0;    ///< frames whose coefficients the GPU summed
  std::size_t mergedOnGpu = 0;       ///< brackets the GPU merged
  std::size_t backgroundsOnGpu = 0;  ///< of those, handed over kept on the GPU (Background::onGpu)
};

/// Exponential moving average of coefficients: alpha = 1 - exp(-dt / tau). Exact on SH because
/// projection is linear (the average of projections is the projection of the average frame).
/// For a step change it reaches 63% after tau seconds: that is the latency it adds.
class ShSmoother {
 public:
  explicit ShSmoother(double tauSeconds) : tau_(tauSeconds) {}
  Sh9 update(const Sh9& x, double timestamp);

 private:
  double tau_;
  std::optional<Sh9> state_;
  double last_ = 0;
};

/// Smooths lights as ShSmoother smooths coefficients, with the same alpha: each light is matched
/// to the nearest light of the previous result (within 20 degrees); its direction moves by slerp,
/// its power and radius by the average. A light with no match starts afresh.
class LightSmoother {
 public:
  explicit LightSmoother(double tauSeconds) : tau_(tauSeconds) {}
  std::vector<Light> update(const std::vector<Light>& lights, double timestamp);

 private:
  double tau_;
  std::vector<Light> state_;
  double last_ = 0;
  bool started_ = false;
};

/// Spherical linear interpolation between unit vectors a and b (t in [0, 1]).
glm::vec3 slerp(glm::vec3 a, glm::vec3 b, float t);

class CapturePipeline {
 public:
  CapturePipeline(std::unique_ptr<FrameSource> source, PipelineOptions options);
  ~CapturePipeline();
  CapturePipeline(const CapturePipeline&) = delete;
  CapturePipeline& operator=(const CapturePipeline&) = delete;

  void start();
  /// Stops the capture thread (idempotent).
  void stop();
  /// The newest frame not yet taken, without waiting.
  std::optional<ProcessedFrame> takeLatest();
  /// Waits for the next frame; nullopt when capture has ended and nothing is left.
  std::optional<ProcessedFrame> waitNext();
  /// Pauses capture before its next frame (a replay's Space key); resuming restarts the pacing
  /// clock, so a paused replay does not rush to catch up.
  void setPaused(bool paused);
  /// While paused: capture exactly one more frame.
  void step();
  /// Capture has ended (end of source, frame limit, error or stop).
  bool finished() const { return finished_; }
  PipelineStats stats() const;
  const FrameSource& source() const { return *source_; }

 private:
  // The capture thread: run() loops over these stages, one frame at a time.
  struct Loop;
  void run();
  bool waitForTurn(Loop& s);  ///< the pause / step gate; false when stopping
  bool grab(Loop& s);         ///< the next frame (looping if asked); false at the end
  void merge(Loop& s, ProcessedFrame& out);  ///< a bracket into radiance; the confidence
  /// Below holdBelow, after a good frame: the last good lighting stands (counted).
  bool hold(Loop& s, ProcessedFrame& out);
  /// The frame through its FrameProcessor (lighting, background, stage times), judged, held or
  /// smoothed.
  void project(Loop& s, ProcessedFrame& out);
  /// The followed ball's circle for the frame in hand (the layout refitted where it moved); false
  /// before the ball is first found.
  bool followBall(Loop& s, ProcessedFrame& out);
  void pace(Loop& s, double timestamp);  ///< paced runs: waits for the frame's time
  /// Waits on cv_ until ready(), stop, `until`, or PipelineOptions::interrupted (polled).
  template <class Ready>
  void waitPolling(std::unique_lock<std::mutex>& lock, std::chrono::steady_clock::time_point until,
                   Ready ready);
  void publish(ProcessedFrame&& f);
  std::optional<ProcessedFrame> takeFromSlot(std::unique_lock<std::mutex>& lock);

  std::unique_ptr<FrameSource> source_;
  PipelineOptions opt_;
  std::thread thread_;
  std::atomic<bool> stop_{false}, finished_{false};
  std::atomic<bool> interrupted_{false};  ///< PipelineOptions::interrupted said so
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::optional<ProcessedFrame> slot_;
  PipelineStats stats_;
  bool paused_ = false, resync_ = false;
  int steps_ = 0;
};

}  // namespace lp
