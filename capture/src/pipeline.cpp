#include "liveprobe/capture/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <utility>

#include "liveprobe/capture/ball.h"
#include "liveprobe/capture/resample.h"
#include "liveprobe/hdr/bracketed_source.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/executor.h"

namespace lp {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

glm::vec3 slerp(glm::vec3 a, glm::vec3 b, float t) {
  const float c = std::clamp(glm::dot(a, b), -1.0f, 1.0f);
  const float angle = std::acos(c);
  if (angle < 1e-4f) return glm::normalize(glm::mix(a, b, t));
  const float s = std::sin(angle);
  return glm::normalize(a * (std::sin((1.0f - t) * angle) / s) + b * (std::sin(t * angle) / s));
}

std::vector<Light> LightSmoother::update(const std::vector<Light>& lights, double timestamp) {
  const double dt = timestamp - last_;
  last_ = timestamp;
  if (tau_ <= 0 || !started_ || dt < 0) {  // off, the first frame, or a loop: start afresh
    started_ = true;
    return state_ = lights;
  }
  const float alpha = float(1.0 - std::exp(-dt / tau_));
  std::vector<Light> next = lights;
  for (Light& l : next) {
    const Light* match = nullptr;
    for (const Light& p : state_)
      if (!match || glm::dot(p.dir, l.dir) > glm::dot(match->dir, l.dir)) match = &p;
    if (!match || glm::dot(match->dir, l.dir) < std::cos(glm::radians(20.0f))) continue;
    l.dir = slerp(match->dir, l.dir, alpha);
    l.power = match->power + alpha * (l.power - match->power);
    l.angularRadius = match->angularRadius + alpha * (l.angularRadius - match->angularRadius);
    l.share = match->share + alpha * (l.share - match->share);
  }
  return state_ = next;
}

Sh9 ShSmoother::update(const Sh9& x, double timestamp) {
  if (tau_ <= 0 || !state_) {
    state_ = x;
    last_ = timestamp;
    return x;
  }
  const double dt = timestamp - last_;
  last_ = timestamp;
  // A backwards jump (a loop) restarts the average.
  const float alpha = dt < 0 ? 1.0f : float(1.0 - std::exp(-dt / tau_));
  for (int k = 0; k < kShCount; ++k) state_->c[k] += alpha * (x.c[k] - state_->c[k]);
  return *state_;
}

CapturePipeline::CapturePipeline(std::unique_ptr<FrameSource> source, PipelineOptions options)
    : source_(std::move(source)), opt_(std::move(options)) {}

CapturePipeline::~CapturePipeline() { stop(); }

void CapturePipeline::start() {
  stop_ = false;
  finished_ = false;
  thread_ = std::thread([this] { run(); });
}

void CapturePipeline::stop() {
  {
    std::lock_guard lock(mutex_);  // under the lock, so no waiter misses the wake-up
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) {
    source_->interrupt();  // a source that waits (a network camera reconnecting) ends its next()
    thread_.join();
  }
  // A frame handed over that the consumer never took before the stop: dropped, so that the
  // frames captured are those drawn plus those dropped.
  std::lock_guard lock(mutex_);
  if (slot_) {
    ++stats_.dropped;
    slot_.reset();
  }
}

void CapturePipeline::publish(ProcessedFrame&& f) {
  std::unique_lock lock(mutex_);
  if (opt_.handoff == Handoff::Every) cv_.wait(lock, [&] { return !slot_ || stop_; });
  if (slot_) ++stats_.dropped;  // the consumer never saw it: stale, dropped
  slot_ = std::move(f);
  ++stats_.captured;
  lock.unlock();
  cv_.notify_all();
}

// The capture thread's state from frame to frame.
struct CapturePipeline::Loop {
  explicit Loop(const PipelineOptions& o)
      : processor({o.layout, o.photometry, o.rotation, o.reduce, o.lights}),
        smoother(o.smoothSeconds),
        lightSmoother(o.smoothSeconds),
        wallStart(Clock::now()) {
    if (o.threads > 1) pool = std::make_unique<ThreadPool>(o.threads);
    if (o.bracket) merger.emplace(*o.bracket);
  }
  FrameProcessor processor;  ///< the frame's lighting (liveprobe/capture/frame_processor.h)
  std::optional<BracketMerger> merger;
  std::optional<BallFollower> ball;  ///< PipelineOptions::followBall
  Frame merged;                      ///< the merger's output, swapped into `frame`
  /// Equirect frames without a light search are projected as they merge (their coefficients
  /// here), and the float frame is written only where the display draws it.
  MergeProjection projection;
  bool projected = false;        ///< `frame` was projected as it merged
  bool backgroundOnGpu = false;  ///< its background is where the GPU merged it (Background::onGpu)
  struct Lit {
    Sh9 radiance, unsmoothed;
    std::vector<Light> lights;
    bool brightestMeasured = true;
  };
  std::optional<Lit> lastGood;  ///< the last complete frame over PipelineOptions::holdBelow
  bool holding = false;         ///< lastGood stands in for the frames
  ShSmoother smoother;
  LightSmoother lightSmoother;
  std::unique_ptr<ThreadPool> pool;
  /// The frame in hand. Handed over as the background that shows it as it is (`shown`), it is
  /// the viewer's: the next grab takes a new one, and capture never writes it again.
  std::shared_ptr<Frame> frame = std::make_shared<Frame>();
  bool shown = false;
  std::function<Sh9(const ProjectionJob&)> gpu;       ///< PipelineOptions::projectOnGpu's
  std::function<std::optional<double>()> gpuMergeMs;  ///< GpuWork::mergeMs
  std::function<std::shared_ptr<const gl::GpuImage>()> gpuMergedImage;  ///< GpuWork::mergedImage
  std::uint64_t index = 0;
  Clock::time_point wallStart;
  double streamStart = -1, loopOffset = 0, lastTimestamp = 0;
  double pacedTimestamp = -1;  ///< the last frame's timestamp that pace() saw
};

bool CapturePipeline::waitForTurn(Loop& s) {
  std::unique_lock lock(mutex_);
  waitPolling(lock, Clock::time_point::max(), [&] { return !paused_ || steps_ > 0; });
  if (stop_ || interrupted_) return false;
  if (paused_) --steps_;
  if (std::exchange(resync_, false)) s.streamStart = -1;  // resumed: pace from here
  return true;
}

bool CapturePipeline::grab(Loop& s) {
  if (s.shown) s.frame = std::make_shared<Frame>(), s.shown = false;
  Frame& frame = *s.frame;
  if (!source_->next(frame)) {
    if (!(opt_.loop && source_->rewind() && source_->next(frame))) return false;
    s.loopOffset = s.lastTimestamp + (source_->fps() > 0 ? 1.0 / source_->fps() : 0.0);
  }
  if (opt_.onFrame) opt_.onFrame(frame);
  s.lastTimestamp = frame.timestamp + s.loopOffset;
  return true;
}

void CapturePipeline::merge(Loop& s, ProcessedFrame& out) {
  s.backgroundOnGpu = false;
  if (!s.merger) return;
  s.projected = opt_.layout.layout == Layout::Equirect && opt_.reduce == 1;
  if (s.projected) {
    s.processor.fit(*s.frame);  // the projector of the frame's size
    s.projection.integrals = s.processor.projector()->equirectIntegrals();
    // The display draws the frame where the GPU merged it, where it can; the light search reads
    // it here.
    s.projection.keepWhereMerged = opt_.keepImages && s.gpuMergedImage;
    s.projection.keepFrame =
        opt_.lights.maxLights > 0 || (opt_.keepImages && !s.projection.keepWhereMerged);
    out.confidence = s.merger->add(*s.frame, s.merged, s.pool.get(), s.projection);
  } else {
    out.confidence = s.merger->add(*s.frame, s.merged, s.pool.get());
  }
  std::swap(*s.frame, s.merged);
  if (!s.merger->hasFrameKernel()) return;
  out.mergedOnGpu = true;
  if (s.gpuMergeMs) out.gpu.merge = s.gpuMergeMs();
  s.backgroundOnGpu = s.projected && s.projection.keepWhereMerged;
  if (s.backgroundOnGpu) {
    Background& b = out.background;
    b.onGpu = s.gpuMergedImage();
    b.onGpuWidth = s.frame->width, b.onGpuHeight = s.frame->height;
    b.layout = Layout::Equirect;
    b.scale = float(s.frame->radianceScale) * opt_.photometry.exposure;
    std::lock_guard lock(mutex_);
    ++stats_.backgroundsOnGpu;
  }
}

bool CapturePipeline::hold(Loop& s, ProcessedFrame& out) {
  // Nothing good yet: the frame as it is. Once held, only a complete bracket that agrees again
  // lets go (a window still holding a frame of the occluder, or missing one, does not).
  // A followed ball lost in the frame holds too, --hold-below or not: nothing of it was measured.
  if ((opt_.holdBelow <= 0 && !s.ball) || !s.lastGood) return false;
  const FrameConfidence& c = out.confidence;
  const bool good = !out.ballLost && c.measured() >= opt_.holdBelow;
  // Agreeing again: whole, and measuring the brightest source where the last good frame did.
  const bool agrees = c.complete && (c.brightestMeasured || !s.lastGood->brightestMeasured);
  s.holding = s.holding ? !(good && agrees) : !good;
  if (!s.holding) return false;
  out.radiance = s.lastGood->radiance;
  out.unsmoothed = s.lastGood->unsmoothed;
  out.lights = s.lastGood->lights;
  out.held = true;
  std::lock_guard lock(mutex_);
  ++stats_.held;
  return true;
}

bool CapturePipeline::followBall(Loop& s, ProcessedFrame& out) {
  const auto& within = opt_.followBall->searchWithin;
  if (!s.ball) s.ball.emplace(within ? within(s.frame->width, s.frame->height) : std::nullopt);
  const BallFollower::Step step = s.ball->follow(*s.frame);
  if (!step.circle) {
    std::lock_guard lock(mutex_);
    ++stats_.beforeBall;
    return false;
  }
  const glm::vec3 circle(float(step.circle->x), float(step.circle->y), float(step.circle->radius));
  if (circle != s.processor.options().layout.circle)
    s.processor.setLayout(opt_.followBall->layoutFor(circle));
  out.ball = circle, out.ballLost = step.lost;
  {
    std::lock_guard lock(mutex_);
    stats_.ballLost += step.lost;
    stats_.ballMoves += step.event == BallFollower::Event::Moved;
  }
  const auto& say = opt_.followBall->say;
  if (!say || step.event == BallFollower::Event::None || step.event == BallFollower::Event::Moved)
    return true;
  char text[200];
  const char* what = step.event == BallFollower::Event::Lost
                         ? "mirror ball lost at frame %llu: keeping --circle %.2f,%.2f,%.2f"
                     : step.event == BallFollower::Event::Found
                         ? "mirror ball found at frame %llu: --circle %.2f,%.2f,%.2f"
                         : "mirror ball found again at frame %llu: --circle %.2f,%.2f,%.2f";
  std::snprintf(text, sizeof text, what, static_cast<unsigned long long>(out.sequence + 1),
                step.circle->x, step.circle->y, step.circle->radius);
  say(text);
  return true;
}

void CapturePipeline::project(Loop& s, ProcessedFrame& out) {
  FrameResult r;
  try {
    r = s.processor.run(
        s.frame,
        {.background = opt_.keepImages && !s.backgroundOnGpu,
         .saturation = true,
         .projected = s.projected ? std::optional(s.projection.coefficients) : std::nullopt,
         .projectedPeaks = s.projected ? &s.projection.rowPeaks : nullptr,
         .projectWith = s.gpu},
        s.pool.get());
  } catch (const Error& e) {
    throw Error(source_->describe() + ": frame " + std::to_string(out.index + 1) + ": " + e.what());
  }
  out.times += r.times;
  out.saturated = r.saturated;
  // A bracket projected as it merged was projected where it was merged.
  out.projectedOn = s.projected && out.mergedOnGpu ? ProjectedOn::Gpu : r.projectedOn;
  out.gpu.project = r.gpuProjectMs;
  {
    std::lock_guard lock(mutex_);
    stats_.projectedOnGpu += out.projectedOn == ProjectedOn::Gpu;
    stats_.mergedOnGpu += out.mergedOnGpu;
  }
  if (!s.backgroundOnGpu) out.background = std::move(r.background);
  s.shown = out.background.raw != nullptr;
  FrameLighting& lit = r.lighting;
  // A merged bracket judged itself; a single frame is judged by its clipped pixels. A bracket
  // whose brightest pixel clipped in every exposure has its strongest light's power as a lower
  // bound, as an 8-bit frame's clipped light has.
  if (!s.merger) {
    // Without values at 255 the frame is trusted whole.
    if (out.saturated > 0) out.confidence = s.processor.confidence(*s.frame, lit);
  } else {
    if (!out.confidence.brightestMeasured && !lit.lights.empty()) lit.lights.front().clipped = true;
    const FrameConfidence& c = out.confidence;
    if (c.exposures > 1 || c.agreement < 1) {
      std::lock_guard lock(mutex_);
      ++stats_.mergesTelling;
      stats_.mergesDisagreeing += c.agreement < 0.5;
    }
  }
  if (const Projector* p = s.processor.projector()) out.confidence.coverage = p->coverage();
  if (out.ballLost) out.confidence.agreement = 0, out.confidence.complete = false;
  // Below --hold-below the last good lighting stands, and the smoothing does not see the frame.
  if (hold(s, out)) return;
  out.unsmoothed = lit.radiance;
  out.lights = s.lightSmoother.update(lit.lights, out.timestamp);
  out.radiance = s.smoother.update(lit.radiance, out.timestamp);
  if ((opt_.holdBelow > 0 || s.ball) && !out.ballLost &&
      out.confidence.measured() >= opt_.holdBelow && out.confidence.complete)
    s.lastGood =
        Loop::Lit{out.radiance, out.unsmoothed, out.lights, out.confidence.brightestMeasured};
}

template <class Ready>
void CapturePipeline::waitPolling(std::unique_lock<std::mutex>& lock, Clock::time_point until,
                                  Ready ready) {
  const auto poll =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kStopPollSeconds));
  while (!stop_ && !ready()) {
    if (opt_.interrupted && opt_.interrupted()) {
      interrupted_ = true;
      return;
    }
    const auto now = Clock::now();
    if (now >= until) return;
    cv_.wait_until(lock, until - now > poll ? now + poll : until);
  }
}

void CapturePipeline::pace(Loop& s, double timestamp) {
  if (!opt_.realtime) return;
  if (s.streamStart < 0) s.streamStart = timestamp, s.wallStart = Clock::now();
  // A gap beyond reason (a sidecar's timestamps jumping by days) is not waited out: the stream's
  // clock moves on by one frame interval instead.
  const double gap = timestamp - s.pacedTimestamp;
  const double interval = source_->fps() > 0 ? 1.0 / source_->fps() : 0.0;
  if (s.pacedTimestamp >= 0 && gap > std::max(opt_.maxGapSeconds, 10 * interval)) {
    s.streamStart += gap - interval;
    std::lock_guard lock(mutex_);
    ++stats_.gapsShortened;
  }
  s.pacedTimestamp = timestamp;
  const auto due = s.wallStart + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(timestamp - s.streamStart));
  std::unique_lock lock(mutex_);
  waitPolling(lock, due, [] { return false; });
}

void CapturePipeline::run() {
  Loop s(opt_);
  try {
    if (opt_.projectOnGpu) {
      GpuWork work = opt_.projectOnGpu();
      s.gpu = std::move(work.project);
      if (s.merger && work.merge) {
        s.merger->setFrameKernel(std::move(work.merge), work.mergeTurns,
                                 std::move(work.mergeLuminance));
        s.gpuMergedImage = std::move(work.mergedImage);
      }
      s.gpuMergeMs = std::move(work.mergeMs);
    }
    while (!stop_ && !interrupted_ &&
           (opt_.maxFrames < 0 || std::int64_t(s.index) < opt_.maxFrames)) {
      if (!waitForTurn(s)) break;
      StageClock clock;
      if (!grab(s)) break;
      clock.lap(Stage::Grab);
      const double grabbed = monotonicSeconds();
      ProcessedFrame out;
      out.index = s.index++;
      out.sequence = s.frame->sequence;
      out.reconnects = source_->reconnects();
      out.width = s.frame->width, out.height = s.frame->height;
      out.timestamp = s.lastTimestamp;
      if (s.merger) {
        merge(s, out);
        clock.lap(Stage::Merge);
      }
      if (opt_.followBall && !followBall(s, out)) {
        --s.index;  // not projected: the frames counted are the ball's
        continue;
      }
      out.times = clock.times;
      project(s, out);  // convert, project and resample: FrameProcessor::run's times
      out.captureTime = s.frame->captureTime >= 0 ? s.frame->captureTime : grabbed;
      out.coefficientsLatencyMs = 1000.0 * (monotonicSeconds() - out.captureTime);
      pace(s, out.timestamp);
      if (interrupted_) break;  // the frame whose time had not come is not handed over
      // Its record goes out at its time, and only when it is handed over: the sinks' counts
      // and --coeffs-out's lines are the frames captured.
      if (opt_.onCaptured) opt_.onCaptured(out);
      publish(std::move(out));
    }
  } catch (const std::exception& e) {
    std::lock_guard lock(mutex_);
    stats_.error = e.what();
  }
  {
    std::lock_guard lock(mutex_);
    stats_.skipped = source_->skippedFrames();
    if (const BracketedSource* b = bracketOf(*source_)) {
      stats_.unidentified = b->unidentifiedFrames();
      stats_.unidentifiedReport = b->unidentifiedReport();
    }
    stats_.endReason = source_->endReason();
    stats_.reconnects = source_->reconnects();
    stats_.stale = source_->staleFrames();
    finished_ = true;
  }
  cv_.notify_all();
}

std::optional<ProcessedFrame> CapturePipeline::takeFromSlot(std::unique_lock<std::mutex>& lock) {
  if (!slot_) return std::nullopt;
  std::optional<ProcessedFrame> f = std::move(slot_);
  slot_.reset();
  ++stats_.taken;
  lock.unlock();
  cv_.notify_all();  // a capture thread waiting in Handoff::Every may go on
  return f;
}

std::optional<ProcessedFrame> CapturePipeline::takeLatest() {
  std::unique_lock lock(mutex_);
  return takeFromSlot(lock);
}

std::optional<ProcessedFrame> CapturePipeline::waitNext() {
  std::unique_lock lock(mutex_);
  cv_.wait(lock, [&] { return slot_ || finished_ || stop_; });
  return takeFromSlot(lock);
}

void CapturePipeline::setPaused(bool paused) {
  {
    std::lock_guard lock(mutex_);
    if (paused_ && !paused) resync_ = true;
    paused_ = paused;
    steps_ = 0;
  }
  cv_.notify_all();
}

void CapturePipeline::step() {
  {
    std::lock_guard lock(mutex_);
    ++steps_;
    resync_ = true;
  }
  cv_.notify_all();
}

PipelineStats CapturePipeline::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

}  // namespace lp
