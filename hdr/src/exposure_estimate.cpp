#include "liveprobe/hdr/exposure_estimate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "liveprobe/sh/error.h"

namespace lp {

namespace {
// Codes measured well: above the noise and half an 8-bit step under 5% of the value, under the
// clip and a JPEG's ringing near it.
constexpr int kLowest = 16, kHighest = 245;
// About this many samples per frame (a grid): the median of their log ratios is exact to well
// under 1%, at a cost that does not grow with the frame.
constexpr std::size_t kSamples = 16384;
// The frames before the newest kept to measure it against: a bracket of five and one more.
constexpr std::size_t kKnown = 6;
// How closely a ratio of two frames is measured (8-bit steps, JPEG noise; 1.2% seen on MJPEG).
constexpr double kPrecision = 0.02;
}  // namespace

ExposureIdentifier::ExposureIdentifier(std::vector<double> asked, CameraResponse response)
    : asked_(std::move(asked)), response_(std::move(response)) {}

void ExposureIdentifier::seed(const Frame& frame, double base) {
  if (!(base > 0)) throw Error("the exposure in force before a bracket must be positive");
  base_ = base;
  candidates_ = asked_;
  candidates_.push_back(base_);
  std::sort(candidates_.begin(), candidates_.end());
  candidates_.erase(std::unique(candidates_.begin(), candidates_.end()), candidates_.end());
  // Half the smallest gap between two candidates, at most 0.3 stops: an estimate is named after
  // one exposure or none.
  tolerance_ = 0.3;
  for (std::size_t i = 1; i < candidates_.size(); ++i)
    tolerance_ = std::min(tolerance_, 0.5 * std::log2(candidates_[i] / candidates_[i - 1]));
  known_.clear();
  remember(frame, base_);
}

ExposureIdentifier::Known ExposureIdentifier::sample(const Frame& f) const {
  if (f.format != PanoramaFormat::BgrU8)
    throw Error("exposures are estimated from 8-bit frames; this frame is already radiance");
  const std::size_t pixels = std::size_t(f.width) * std::size_t(f.height);
  const int step = std::max(1, int(std::lround(std::sqrt(double(pixels) / double(kSamples)))));
  Known k;
  k.linear.reserve(pixels / std::size_t(step * step) + std::size_t(f.width));
  const auto& green = response_.linear[1];
  for (int y = step / 2; y < f.height; y += step)
    for (int x = step / 2; x < f.width; x += step) {
      const std::uint8_t* px = &f.bgr8[(std::size_t(y) * std::size_t(f.width) + x) * 3];
      const std::uint8_t code = px[1];
      // Green read well, and no channel near its clip: a clipped red or blue pulls green with it
      // through a camera's YUV (4:2:2 or 4:2:0 chroma shared by neighbours), by several percent.
      const bool well =
          code >= kLowest && code <= kHighest && std::max({px[0], px[1], px[2]}) <= kHighest;
      k.linear.push_back(well ? green[code] : 0.0f);
      // An interval with room for 8-bit steps and compression: a dark code is below what would
      // read kLowest, a clipped one above kHighest's value, a low one within a factor of two.
      constexpr float kInf = std::numeric_limits<float>::infinity();
      k.lo.push_back(code > kHighest  ? green[kHighest]
                     : code < kLowest ? 0.0f
                                      : green[code] / 1.25f);
      k.hi.push_back(code > kHighest  ? kInf
                     : code < 7       ? green[kLowest]
                     : code < kLowest ? 2.0f * green[code]
                                      : 1.25f * green[code]);
    }
  return k;
}

void ExposureIdentifier::remember(const Frame& frame, double seconds) {
  Known k = sample(frame);
  k.seconds = seconds;
  known_.push_back(std::move(k));
  if (known_.size() > kKnown) known_.pop_front();
}

std::optional<double> ExposureIdentifier::identify(const Frame& frame) {
  Known now = sample(frame);
  lastEstimate_ = 0;
  if (known_.empty()) return std::nullopt;  // not seeded
  std::optional<double> seconds = byRatio(now);
  // A ratio speaks for the pixels both frames measured well; the rest must not contradict it
  // (a frame torn between two exposures can have one half the ratio cannot see).
  if (seconds) {
    const std::vector<double> share = contradicted(now, {*seconds});
    if (!share.empty() && share[0] > 0.05) return std::nullopt;
  }
  if (!seconds && lastEstimate_ == 0) seconds = byContradiction(now);
  if (!seconds) return std::nullopt;
  now.seconds = *seconds;
  known_.push_back(std::move(now));
  if (known_.size() > kKnown) known_.pop_front();
  return seconds;
}

std::optional<double> ExposureIdentifier::ratioEstimate(const Known& now) const {
  // Against the known frame that shares the most well-measured samples with this one.
  std::vector<float> logs, best;
  double bestSeconds = 0;
  for (auto it = known_.rbegin(); it != known_.rend(); ++it) {
    if (it->linear.size() != now.linear.size()) continue;  // another size: not comparable
    logs.clear();
    for (std::size_t i = 0; i < now.linear.size(); ++i)
      if (now.linear[i] > 0 && it->linear[i] > 0)
        logs.push_back(std::log(now.linear[i] / it->linear[i]));
    if (logs.size() > best.size()) std::swap(logs, best), bestSeconds = it->seconds;
  }
  if (best.size() < std::max<std::size_t>(32, now.linear.size() / 200)) return std::nullopt;
  const auto mid = best.begin() + std::ptrdiff_t(best.size() / 2);
  std::nth_element(best.begin(), mid, best.end());
  return bestSeconds * std::exp(double(*mid));
}

std::optional<double> ExposureIdentifier::byRatio(Known& now) {
  const std::optional<double> measured = ratioEstimate(now);
  if (!measured) return std::nullopt;
  const double estimate = *measured;
  lastEstimate_ = estimate;
  const auto nearest =
      std::min_element(candidates_.begin(), candidates_.end(), [&](double a, double b) {
        return std::abs(std::log2(estimate / a)) < std::abs(std::log2(estimate / b));
      });
  if (std::abs(std::log2(estimate / *nearest)) > tolerance_) return std::nullopt;
  // Within the estimate's own precision (8-bit steps, a codec's noise), the exposure asked (or
  // the base, the anchor) stands; beyond it, the camera rounded, and the estimate is the truth.
  return std::abs(estimate / *nearest - 1.0) <= kPrecision ? *nearest : estimate;
}

std::optional<double> ExposureIdentifier::measure(const Frame& frame) {
  measured_ = sample(frame);
  const std::optional<double> estimate = ratioEstimate(*measured_);
  lastEstimate_ = estimate.value_or(0.0);
  return estimate;
}

double ExposureIdentifier::contradiction(double seconds) const {
  if (!measured_) return 0;
  const std::vector<double> share = contradicted(*measured_, {seconds});
  return share.empty() ? 0.0 : share[0];
}

void ExposureIdentifier::confirm(double seconds, bool alone) {
  if (!measured_) return;
  if (alone) known_.clear();
  measured_->seconds = seconds;
  known_.push_back(std::move(*measured_));
  measured_.reset();
  if (known_.size() > kKnown) known_.pop_front();
}

std::vector<double> ExposureIdentifier::contradicted(const Known& now,
                                                     const std::vector<double>& times) const {
  // Per exposure, the share of samples where this frame, taken at it, and a known frame cannot
  // both hold (their intervals of scene radiance are disjoint), over the newest known frame of
  // each exposure.
  std::vector<const Known*> against;
  for (auto it = known_.rbegin(); it != known_.rend(); ++it)
    if (it->lo.size() == now.lo.size() &&
        std::none_of(against.begin(), against.end(),
                     [&](const Known* k) { return k->seconds == it->seconds; }))
      against.push_back(&*it);
  std::vector<double> share;
  if (against.empty() || now.lo.empty()) return share;
  for (const double t : times) {
    std::size_t n = 0;
    for (const Known* k : against) {
      const float q = float(t / k->seconds);  // this frame's linear over the known one's
      for (std::size_t i = 0; i < now.lo.size(); ++i)
        n += now.lo[i] > k->hi[i] * q || now.hi[i] < k->lo[i] * q;
    }
    share.push_back(double(n) / double(against.size() * now.lo.size()));
  }
  return share;
}

std::optional<double> ExposureIdentifier::byContradiction(const Known& now) const {
  const std::vector<double> share = contradicted(now, candidates_);
  if (share.empty()) return std::nullopt;
  // One exposure explains the frame (at most 2% of it contradicted: motion), and every other
  // is contradicted clearly more: three times as much, and 8 samples more (two dark frames of
  // a sunlit sky differ at the sun alone, a few pixels).
  const auto best = std::size_t(std::min_element(share.begin(), share.end()) - share.begin());
  if (share[best] > 0.02) return std::nullopt;
  const double margin = 8.0 / double(now.lo.size());
  for (std::size_t i = 0; i < share.size(); ++i)
    if (i != best && share[i] < 3 * share[best] + margin) return std::nullopt;
  return candidates_[best];
}

}  // namespace lp
