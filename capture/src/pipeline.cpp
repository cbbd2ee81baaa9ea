#include "liveprobe/capture/pipeline.h"

#include <chrono>
#include <cmath>
#include <utility>

#include "liveprobe/capture/resample.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/executor.h"

namespace lp {

namespace {
using Clock = std::chrono::steady_clock;
double msBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}
}  // namespace

bool displayTakesFrameAsIs(const Frame& frame, const Photometry& photometry,
                           const LayoutSpec& layout) {
  return frame.format == PixelFormat::Bgr8 && photometry.gamma == 0.0f &&
         (layout.layout == Layout::Equirect || layout.layout == Layout::Angular);
}

Sh9 projectFrame(const Projector& projector, const Frame& frame, const Linearizer& linearizer,
                 Executor* executor) {
  if (frame.format == PixelFormat::Bgr8)
    return projector.project(PanoramaView::bgrU8(frame.bgr8.data(), frame.width, frame.height,
                                                 linearizer.table().data(), projector.spec()),
                             executor);
  return projector.project(
             PanoramaView::rgbF32(frame.rgb.data(), frame.width, frame.height, projector.spec()),
             executor) *
         linearizer.exposure();
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
  if (thread_.joinable()) thread_.join();
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

void CapturePipeline::run() {
  // The source's radiance scale (a recording's stored exposure, a camera's exposure time) may
  // change from frame to frame: it is read per frame and applied to the coefficients (projection
  // is linear) and to the display copy.
  const Linearizer linearizer(opt_.photometry);
  std::optional<Projector> projector;
  ShSmoother smoother(opt_.smoothSeconds);
  std::unique_ptr<ThreadPool> pool;
  if (opt_.threads > 1) pool = std::make_unique<ThreadPool>(opt_.threads);
  Frame frame;
  std::uint64_t index = 0;
  Clock::time_point wallStart = Clock::now();
  double streamStart = -1, loopOffset = 0, lastTimestamp = 0;
  try {
    while (!stop_ && (opt_.maxFrames < 0 || std::int64_t(index) < opt_.maxFrames)) {
      {
        std::unique_lock lock(mutex_);
        cv_.wait(lock, [&] { return !paused_ || steps_ > 0 || stop_; });
        if (stop_) break;
        if (paused_) --steps_;
        if (std::exchange(resync_, false)) streamStart = -1;
      }
      const auto t0 = Clock::now();
      if (!source_->next(frame)) {
        if (opt_.loop && source_->rewind() && source_->next(frame)) {
          loopOffset = lastTimestamp + (source_->fps() > 0 ? 1.0 / source_->fps() : 0.0);
        } else {
          break;
        }
      }
      const auto t1 = Clock::now();
      if (opt_.onFrame) opt_.onFrame(frame);
      const double timestamp = frame.timestamp + loopOffset;
      lastTimestamp = timestamp;
      const int reduce = opt_.reduce;
      if (!projector || projector->width() * reduce != frame.width ||
          projector->height() * reduce != frame.height) {
        if (auto why = layoutMismatch(opt_.layout, frame.width, frame.height); !why.empty())
          throw Error(source_->describe() + ": " + std::string(layoutName(opt_.layout.layout)) +
                      " layout: " + why);
        if (reduce > 1 && (opt_.layout.layout != Layout::Equirect || frame.width % reduce ||
                           frame.height % reduce))
          throw Error(source_->describe() + ": --reduce " + std::to_string(reduce) +
                      " needs an equirect frame whose size is a multiple of it");
        projector.emplace(opt_.layout, frame.width / reduce, frame.height / reduce);
      }
      // Convert: a linear copy only for display. The projection reads the frame itself: 8-bit
      // through the lookup table, float scaled afterwards (projection is linear).
      std::shared_ptr<Image> image;
      std::shared_ptr<Frame> raw;
      std::size_t saturated = 0;
      if (opt_.keepImages && displayTakesFrameAsIs(frame, opt_.photometry, opt_.layout)) {
        raw = std::make_shared<Frame>(frame);  // the display decodes it: no linear copy
        saturated = countSaturated(frame);
      } else if (opt_.keepImages) {
        image = std::make_shared<Image>();
        saturated = linearizer.convert(frame, *image);
      } else {
        saturated = countSaturated(frame);
      }
      const auto t2 = Clock::now();
      Sh9 sh;
      if (reduce > 1) {
        if (!image) {
          image = std::make_shared<Image>();
          linearizer.convert(frame, *image);
        }
        const Image small = reduceEquirect(image->rgb.data(), image->width, image->height, reduce);
        sh = projector->project(PanoramaView::rgbF32(small.rgb.data(), small.width, small.height),
                                pool.get());
      } else {
        sh = projectFrame(*projector, frame, linearizer, pool.get());
      }
      const double scale = frame.radianceScale;  // the exposure in force for this frame
      if (scale != 1.0) {
        sh *= float(scale);
        if (image)
          for (float& v : image->rgb) v *= float(scale);
      }
      const float rawScale = float(scale) * opt_.photometry.exposure;
      if (opt_.rotation) sh = rotateSh(sh, *opt_.rotation);
      const Sh9 unsmoothed = sh;
      sh = smoother.update(sh, timestamp);
      const auto t3 = Clock::now();

      ProcessedFrame out;
      out.index = index++;
      out.sequence = frame.sequence;
      out.timestamp = timestamp;
      out.radiance = sh;
      out.unsmoothed = unsmoothed;
      if (opt_.keepImages && !raw) out.image = std::move(image);  // one background per frame
      out.raw = std::move(raw);
      out.rawScale = rawScale;
      out.displayScale = frame.format == PixelFormat::Bgr8 ? rawScale : 0.0f;
      out.times = {msBetween(t0, t1), msBetween(t1, t2), msBetween(t2, t3)};
      out.saturated = saturated;
      if (opt_.onCaptured) opt_.onCaptured(out);
      if (opt_.realtime) {
        if (streamStart < 0) streamStart = timestamp, wallStart = Clock::now();
        const auto due = wallStart + std::chrono::duration_cast<Clock::duration>(
                                         std::chrono::duration<double>(timestamp - streamStart));
        std::unique_lock lock(mutex_);
        cv_.wait_until(lock, due, [&] { return bool(stop_); });
      }
      publish(std::move(out));
    }
  } catch (const std::exception& e) {
    std::lock_guard lock(mutex_);
    stats_.error = e.what();
  }
  {
    std::lock_guard lock(mutex_);
    stats_.skipped = source_->skippedFrames();
    stats_.endReason = source_->endReason();
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
