#include "liveprobe/hdr/bracketing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "liveprobe/hdr/exposure_estimate.h"
#include "liveprobe/sh/error.h"

namespace lp {

namespace {
// The lags a schedule is searched over: a control delay of up to 6 frames, plus the frame.
constexpr int kMaxLag = 7;
// The exposures seen that a lag is locked or re-locked on, and how many stay known.
constexpr std::size_t kSeenKept = 16;
std::string stopName(double ev) {
  char text[32];
  std::snprintf(text, sizeof text, "%+g EV", ev);
  return text;
}
}  // namespace

Bracketing::Bracketing(ExposureControl& control, BracketOptions options)
    : control_(control), opt_(std::move(options)) {
  if (!(opt_.locked > 0))
    throw Error(opt_.name + ": bracketing needs a locked exposure (lockExposure)");
  const auto [lo, hi] = control_.exposureRange();
  least_ = lo;
  for (const double stop : opt_.stops) {
    const double want = opt_.locked * std::exp2(stop);
    asked_.push_back(std::int32_t(std::clamp<double>(std::lround(want), lo, hi)));
  }
  base_ = opt_.locked * 1e-4;
  contradicted_.assign(asked_.size() + 1, 0);
  if (opt_.response.controlDelay) lag_ = *opt_.response.controlDelay + 1;
}

Bracketing::~Bracketing() = default;

void Bracketing::start(Frame& anchor) {
  if (!anchor.exposureReported) {
    std::vector<double> asked;
    for (const std::int32_t e : asked_) asked.push_back(e * 1e-4);
    identifier_ = std::make_unique<ExposureIdentifier>(std::move(asked), opt_.response);
    identifier_->seed(anchor, base_);  // the locked exposure, as written
  }
  const double seconds = anchor.exposureReported ? 1.0 / anchor.radianceScale : base_;
  name(anchor, seconds);
  note(anchor.sequence, seconds);
  next_ = 0;
  askNext(anchor.sequence);
}

int Bracketing::scheduled(std::uint64_t sequence, int lag) const {
  // The newest exposure asked at least `lag` frames before this one.
  for (auto it = writes_.rbegin(); it != writes_.rend(); ++it)
    if (it->after + std::uint64_t(lag) <= sequence) return it->stop;
  return -1;
}

double Bracketing::seconds(int stop) const {
  return stop < 0 ? base_ : asked_[std::size_t(stop)] * 1e-4;
}

int Bracketing::nearestStop(double measured) const {
  int best = -1;
  for (int k = 0; k < int(asked_.size()); ++k)
    if (std::abs(std::log2(measured / seconds(k))) < std::abs(std::log2(measured / seconds(best))))
      best = k;
  return best;
}

bool Bracketing::nearest(double measured, int stop) const {
  // A ratio measured on few shared pixels, or through a response that is not quite the
  // camera's, can be off by half a stop (a -7 EV frame against a 0 EV one); what it cannot do
  // is land nearer another exposure.
  return seconds(nearestStop(measured)) == seconds(stop);
}

bool Bracketing::explains(int lag, const Seen& s) const {
  return nearest(s.seconds, scheduled(s.sequence, lag));
}

std::optional<int> Bracketing::explaining(std::size_t count) const {
  const std::size_t from = count == 0 || count > seen_.size() ? 0 : seen_.size() - count;
  for (int lag = 1; lag <= kMaxLag; ++lag)
    if (std::all_of(seen_.begin() + std::ptrdiff_t(from), seen_.end(),
                    [&](const Seen& s) { return explains(lag, s); }))
      return lag;
  return std::nullopt;
}

void Bracketing::setLag(int lag) {
  const bool calibrated = opt_.response.controlDelay.has_value();
  lag_ = lag;
  if (calibrated && lag - 1 != *opt_.response.controlDelay && !warned_ && opt_.onWarning) {
    warned_ = true;
    const int delay = lag - 1;
    opt_.onWarning(opt_.name + ": a new exposure showed " + std::to_string(delay) + " frame" +
                   (delay == 1 ? "" : "s") +
                   " after it was asked; the calibration (--response) measured " +
                   std::to_string(*opt_.response.controlDelay) +
                   " (another mode, frame rate or camera? each frame is still merged at the "
                   "exposure it was taken with)");
  }
}

void Bracketing::lockLag() {
  // The last exposures seen (a cycle and one more, at least four, two of them distinct)
  // explained by one lag and by no other.
  const std::size_t window = std::min(seen_.size(), std::max<std::size_t>(4, asked_.size() + 1));
  if (!varied_ || window < 4) return;
  const auto from = seen_.end() - std::ptrdiff_t(window);
  if (std::all_of(from, seen_.end(),
                  [&](const Seen& s) { return std::abs(s.seconds / from->seconds - 1) < 0.02; }))
    return;  // one exposure throughout: no lag is told from another
  int only = 0;
  for (int lag = 1; lag <= kMaxLag; ++lag)
    if (std::all_of(from, seen_.end(), [&](const Seen& s) { return explains(lag, s); })) {
      if (only) return;  // two lags explain what was seen: not yet told apart
      only = lag;
    }
  if (only) setLag(only);
}

void Bracketing::relock() {
  // The last two exposures seen contradict the lag in force, and another explains the last
  // cycle's: the schedule slipped.
  if (seen_.size() < 2 || explains(*lag_, seen_.back()) || explains(*lag_, seen_[seen_.size() - 2]))
    return;
  if (const auto lag = explaining(std::max<std::size_t>(3, asked_.size() + 1)))
    if (*lag != *lag_) setLag(*lag);
}

void Bracketing::note(std::uint64_t sequence, double seconds) {
  seen_.push_back({sequence, seconds});
  if (seen_.size() > kSeenKept) seen_.pop_front();
  if (first_ == 0) first_ = seconds;
  varied_ = varied_ || std::abs(seconds - first_) > 0.02 * first_;
}

void Bracketing::askNext(std::uint64_t after) {
  control_.requestExposure(asked_[next_]);
  writes_.push_back({after, int(next_)});
  if (writes_.size() > std::size_t(2 * kMaxLag)) writes_.pop_front();
  next_ = (next_ + 1) % asked_.size();
}

void Bracketing::name(Frame& frame, double seconds) const {
  frame.radianceScale = 1.0 / seconds;
  frame.exposure100us = std::int32_t(std::lround(seconds * 1e4));
}

void Bracketing::checkFollows(const Frame& frame) {
  // A camera that ignores the control shows one exposure, frame after frame.
  if (++taken_ != 4 * asked_.size() + 10 || varied_) return;
  throw Error(opt_.name + ": the camera ignores its exposure control: " + std::to_string(taken_) +
              " frames all " + (frame.exposureReported ? "report " : "show ") +
              std::to_string(std::lround(first_ * 1e4)) + " x 100 us");
}

bool Bracketing::take(Frame& frame) {
  const std::uint64_t s = frame.sequence;
  bool deliver = false;
  if (frame.exposureReported) {
    // What the camera says this frame was taken with always wins.
    note(s, 1.0 / frame.radianceScale);
    deliver = true;
    if (!lag_)
      lockLag();
    else
      relock();
  } else if (!lag_) {
    // Not yet the schedule: the pixels name the exposure, against the frames known before.
    const auto t = identifier_ ? identifier_->identify(frame) : std::nullopt;
    // What they measured tells the lag even where it named no exposure (a frame the known ones
    // contradict in part: the scene moved).
    const double measured = t ? *t : (identifier_ ? identifier_->lastEstimate() : 0.0);
    if (measured > 0) note(s, measured);
    lockLag();
    if (t) {
      name(frame, seconds(nearestStop(*t)));  // as asked, as the schedule names them
      deliver = true;
    } else if (lag_ && measured > 0 && explains(*lag_, seen_.back())) {
      name(frame, seconds(scheduled(s, *lag_)));  // the frame that told the lag
      deliver = true;
    } else {
      ++unnamed_;
    }
  } else {
    const std::optional<double> measured = identifier_ ? identifier_->measure(frame) : std::nullopt;
    if (measured) {
      note(s, *measured);
      relock();
    }
    const int now = scheduled(s, *lag_);  // after any re-lock
    const double want = seconds(now);
    if (!measured) {
      // The pixels cannot say (a dark or white frame, a stop far from the known ones): the
      // schedule names it; it is a reference for later frames where nothing contradicts it.
      deliver = true;
      if (identifier_ && identifier_->contradiction(want) <= 0.05) identifier_->confirm(want);
    } else if (nearest(*measured, now)) {
      deliver = true;
      identifier_->confirm(want);
    } else if (++run_ > 2 * asked_.size() + 2) {
      // Contradicted frame after frame, and no lag explains it: the scene changed past what
      // the known frames can be compared with. The schedule stands; the frames known start
      // again from this one.
      deliver = true;
      identifier_->confirm(want, true);
    } else {
      ++contradicted_[now < 0 ? asked_.size() : std::size_t(now)];
    }
    if (deliver) name(frame, want);
  }
  if (deliver) run_ = 0, watchClip(frame);
  checkFollows(frame);
  askNext(s);
  // A camera whose lag could not be told from the first frames: the lag that explains most.
  if (!lag_ && taken_ >= 4 * asked_.size() + 10) {
    int best = 1;
    std::size_t most = 0;
    for (int lag = 1; lag <= kMaxLag; ++lag) {
      const auto n = std::size_t(std::count_if(seen_.begin(), seen_.end(),
                                               [&](const Seen& x) { return explains(lag, x); }));
      if (n > most) most = n, best = lag;
    }
    setLag(best);
  }
  return deliver;
}

void Bracketing::watchClip(const Frame& frame) {
  if (clipTold_ || !opt_.onWarning || frame.format != PanoramaFormat::BgrU8 || asked_.size() < 2)
    return;
  // The cycle's two shortest distinct exposures.
  std::vector<std::int32_t> order = asked_;
  std::sort(order.begin(), order.end());
  order.erase(std::unique(order.begin(), order.end()), order.end());
  if (order.size() < 2) return;
  const std::size_t which = frame.exposure100us == order[0]   ? 0
                            : frame.exposure100us == order[1] ? 1
                                                              : 2;
  if (which > 1) return;
  const int clip = MergeOptions{}.clipLevel;
  std::size_t n = 0;
  for (std::size_t i = 0; i + 2 < frame.bgr8.size(); i += 3)
    n += std::max({frame.bgr8[i], frame.bgr8[i + 1], frame.bgr8[i + 2]}) >= clip;
  clipped_[which] = n, ++clipSeen_[which];
  if (clipSeen_[0] < 2 || clipSeen_[1] < 2) return;  // the second cycle: past the start-up
  clipTold_ = true;
  if (clipped_[0] == 0) return;
  const auto stopOf = [&](std::int32_t e) {  // as the bracket names it
    for (std::size_t i = 0; i < asked_.size(); ++i)
      if (asked_[i] == e) return stopName(opt_.stops[i]);
    return stopName(std::log2(double(e) / double(opt_.locked)));
  };
  std::string text = opt_.name + ": the brightest light clips even at " + stopOf(order[0]) + " (" +
                     std::to_string(order[0]) + " x 100 us";
  if (order[0] > least_) {
    text +=
        ", the shortest of the bracket): a shorter stop measures it (the control goes down to " +
        std::to_string(least_) + " x 100 us)";
  } else {
    // How far above the clip a clipped light lies is not in the frames: its clipped area
    // shrinking as the exposure falls (a glow) or not (a sharp disk) says nothing of its core.
    // Extrapolating the area asked 7 to 15 stops of a sun that 1 to 3 stops measured.
    text +=
        ", the control's limit): its share is a lower bound (confidence at most 0.5); add "
        "neutral density, a stop at a time, until a run no longer says this (" +
        std::to_string(clipped_[0]) + (clipped_[0] == 1 ? " pixel" : " pixels") + " clipped at " +
        stopOf(order[0]) + ", " + std::to_string(clipped_[1]) + " at " + stopOf(order[1]) + ")";
  }
  opt_.onWarning(text);
}

std::size_t Bracketing::leftOut() const {
  std::size_t n = unnamed_;
  for (const std::size_t c : contradicted_) n += c;
  return n;
}

std::string Bracketing::leftOutReport() const {
  std::string text;
  for (std::size_t i = 0; i < contradicted_.size(); ++i) {
    if (contradicted_[i] == 0) continue;
    text += (text.empty() ? "" : ", ") + std::to_string(contradicted_[i]) + " at " +
            (i < asked_.size() ? stopName(opt_.stops[i]) : std::string("the locked exposure"));
  }
  if (!text.empty()) text += " whose pixels contradicted the exposure asked";
  if (unnamed_ > 0)
    text += (text.empty() ? "" : "; ") + std::to_string(unnamed_) +
            " before the camera's delay was known whose exposure the pixels did not show";
  return text;
}

BracketedCamera::BracketedCamera(std::unique_ptr<FrameSource> camera, ExposureControl& control,
                                 BracketOptions options)
    : camera_(std::move(camera)), bracketing_(control, std::move(options)) {}

void BracketedCamera::start() {
  anchor_ = std::make_unique<Frame>();
  if (!camera_->next(*anchor_)) throw Error(camera_->describe() + ": the stream ended");
  bracketing_.start(*anchor_);
}

bool BracketedCamera::next(Frame& frame) {
  if (anchor_) {  // the first frame, at the locked exposure (or the one it reports)
    std::swap(frame, *anchor_);
    anchor_.reset();
    return true;
  }
  while (camera_->next(frame))
    if (bracketing_.take(frame)) return true;
  return false;
}

}  // namespace lp
