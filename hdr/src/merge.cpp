#include "liveprobe/hdr/merge.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "bracket_align.h"
#include "liveprobe/sh/error.h"
#include "merge_kernel.h"

namespace lp {

// Sums over a merged frame, for its confidence.
struct MergeTally {
  double power = 0, clippedPower = 0;
  /// What the clipped pixels held in the last trusted merge, where more than now (their lower
  /// bound): the light a bracket missing its shortest reading cannot vouch for.
  double clippedEstimate = 0;
  double disagreedPower = 0;
  std::size_t dark = 0;
  float brightest = -1;
  bool brightestClipped = false;
  bool brightestFresh = true;             ///< the newest frame itself read the brightest pixel
  std::array<glm::dvec3, kShCount> sh{};  ///< projecting as it merges: the coefficients' sums
  void add(const MergeTally& o) {
    for (int k = 0; k < kShCount; ++k) sh[k] += o.sh[k];
    power += o.power, clippedPower += o.clippedPower, clippedEstimate += o.clippedEstimate;
    dark += o.dark, disagreedPower += o.disagreedPower;
    if (o.brightest > brightest)
      brightest = o.brightest, brightestClipped = o.brightestClipped,
      brightestFresh = o.brightestFresh;
  }
  FrameConfidence confidence(std::size_t pixels, int exposures) const {
    FrameConfidence c;
    const double estimated = power - clippedPower + clippedEstimate;
    c.clippedShare = estimated > 0 ? clippedEstimate / estimated : 0.0;
    c.darkShare = pixels ? double(dark) / double(pixels) : 0.0;
    c.brightestMeasured = !brightestClipped;
    c.agreement = disagreedPower > 0 ? std::max(0.0, 1.0 - disagreedPower / power) : 1.0;
    c.exposures = exposures;
    return c;
  }
};

namespace {

// Codes from here up are compared for motion: half an 8-bit step is under 5% of the value.
constexpr int kWellExposed = 16;
// Codes from here down are surely below the clip, even after a JPEG's ringing.
constexpr int kSurelyUnclipped = 200;

// Solid angle of an equirect row (sin theta), or 1.
float rowWeight(int y, int h, bool equirect) {
  return equirect ? std::sin(float(M_PI) * (float(y) + 0.5f) / float(h)) : 1.0f;
}

}  // namespace

// The camera's rotation over the window, and what is turned by it: the older frames, and the
// last merges' luminance (each in the orientation of the frame it was merged for).
struct BracketMerger::Alignment {
  explicit Alignment(const CameraResponse& response) : coder(response.linear) {}
  align::RotationTracker tracker;
  align::Coder coder;
  std::array<std::vector<std::uint8_t>, kMaxBracket> turned;
  std::vector<float> previousTurned, referenceTurned;
  std::uint64_t previousSequence = 0, referenceSequence = 0;  ///< the frames they were merged for
  std::vector<std::uint8_t> nearLow, nearHigh;  ///< the newest frame's 3x3 least and most code
  /// The older frames the pixel loop turns itself (setFrameKernel's `turns`): their turns, and
  /// where their pixels read from.
  std::array<std::optional<glm::mat3>, kMaxBracket> byKernel;
  std::array<align::TurnGrid, kMaxBracket> grids;
};

namespace {
// merge::FrameInput::key: one count over every merger of the process, so that no two frames
// share one.
std::atomic<std::uint64_t> frameKeys{0};
// A turn that moves no pixel by more than this is not applied (a still camera's estimate is
// noise of a hundredth of a pixel).
constexpr double kLeastTurnPixels = 0.25;
// The whole-frame check (usableFrames) reads every kCheckStep-th pixel of every kCheckStep-th
// row, from kCheckStep / 2.
constexpr int kCheckStep = 4;
}  // namespace

BracketMerger::BracketMerger(MergeOptions options) : opt_(std::move(options)) {
  if (opt_.frames < 1 || opt_.frames > kMaxBracket)
    throw Error("a bracket merges 1 to " + std::to_string(kMaxBracket) + " frames");
  // Codes the calibration never read count as noise or as clipped.
  opt_.noiseFloor = std::max(opt_.noiseFloor, opt_.response.readFrom - 1);
  opt_.clipLevel = std::min(opt_.clipLevel, opt_.response.readTo + 1);
  if (opt_.align && opt_.equirect && opt_.frames > 1)
    align_ = std::make_unique<Alignment>(opt_.response);
}
BracketMerger::~BracketMerger() = default;
BracketMerger::BracketMerger(BracketMerger&&) noexcept = default;
BracketMerger& BracketMerger::operator=(BracketMerger&&) noexcept = default;

void BracketMerger::push(const Frame& in) {
  if (in.format != PanoramaFormat::BgrU8)
    throw Error("an exposure bracket merges 8-bit frames; this frame is already radiance");
  if (!window_.empty() &&
      (window_.back().width != in.width || window_.back().height != in.height)) {
    window_.clear(), agreements_.clear(), keys_.clear();
    if (align_) align_->tracker.clear();
  }
  // The window keeps copies; the oldest frame's buffer is reused for the newest.
  Frame kept;
  if (window_.size() == std::size_t(opt_.frames)) {
    kept.bgr8 = std::move(window_.front().bgr8);
    window_.pop_front();
    agreements_.pop_front();
    keys_.pop_front();
  }
  kept.bgr8.assign(in.bgr8.begin(), in.bgr8.end());
  kept.sequence = in.sequence, kept.timestamp = in.timestamp;
  kept.width = in.width, kept.height = in.height, kept.format = in.format;
  kept.radianceScale = in.radianceScale, kept.captureTime = in.captureTime;
  kept.exposure100us = in.exposure100us, kept.gain = in.gain;
  window_.push_back(std::move(kept));
  agreements_.push_back(1.0);  // its merge's own agreement, once measured
  keys_.push_back(newKey());
  if (align_ && in.width >= align::kLeastWidth && in.height >= align::kLeastHeight) {
    align_->tracker.add(
        align::logPyramid(in, opt_.response.linear, kWellExposed - 1, opt_.clipLevel),
        in.radianceScale, in.sequence);
  }
}

std::array<const std::uint8_t*, kMaxBracket> BracketMerger::alignedWindow(Executor* executor) {
  std::array<const std::uint8_t*, kMaxBracket> pixels{};
  const int n = int(window_.size());
  if (align_) align_->byKernel = {};
  for (int i = 0; i < n; ++i) {
    const Frame& f = window_[std::size_t(i)];
    pixels[std::size_t(i)] = f.bgr8.data();
    if (!align_ || i == n - 1) continue;
    const glm::mat3 q = align_->tracker.turnSince(f.sequence);
    if (align::displacementPixels(q, f.width) < kLeastTurnPixels) continue;
    // Where the pixel loop turns it (from the frame as taken), only the whole-frame check's grid
    // is turned here.
    auto& turned = align_->turned[std::size_t(i)];
    turned.resize(f.bgr8.size());
    if (kernelTurns_) {
      align_->byKernel[std::size_t(i)] = q;
      const align::TurnGrid& grid = align_->grids[std::size_t(i)] =
          align::turnGrid(f.width, f.height, q);
      align::turnCodes(f.bgr8.data(), f.width, f.height, q, align_->coder, opt_.clipLevel,
                       turned.data(), executor, kCheckStep, &grid);
      continue;
    }
    align::turnCodes(f.bgr8.data(), f.width, f.height, q, align_->coder, opt_.clipLevel,
                     turned.data(), executor);
    pixels[std::size_t(i)] = turned.data();
  }
  return pixels;
}

namespace {

// One frame's reading of one pixel: radiance per channel and its largest code.
struct Reading {
  float e[3];
  float peak;  ///< the largest channel's radiance
  float scale;
  int code;  ///< the largest channel's code
};

enum class Verdict : std::uint8_t { Unknown, Agree, Disagree };

// What one reading says about the radiance (its largest channel), as an interval with room for
// 8-bit steps and compression noise: a mid-range code within 25%, a low code within a factor of
// two, a dark one below what would have read kWellExposed, a clipped one above what would have
// read kSurelyUnclipped. The row kernel (merge_kernel.cpp) applies the same rule per pixel; this
// one judges whole frames on a sparse grid (usableFrames).
struct Judge {
  int floor, clip;
  float wellLinear, belowClipLinear;  ///< linear at kWellExposed and at kSurelyUnclipped

  bool well(const Reading& r) const { return r.code >= kWellExposed && r.code < clip; }
  std::pair<float, float> bounds(const Reading& r) const {
    constexpr float kInf = std::numeric_limits<float>::infinity();
    if (r.code <= floor) return {0.0f, wellLinear * r.scale};
    if (r.code >= clip) return {belowClipLinear * r.scale, kInf};
    const float k = well(r) ? 1.25f : 2.0f;
    return {r.peak / k, r.peak * k};
  }
  // Whether an older reading and the newest tell the same story. Both well exposed, the common
  // case, is a ratio; otherwise their intervals must meet.
  Verdict operator()(const Reading& old, const Reading& now) const {
    if (well(old) && well(now)) {
      const float q = old.peak / now.peak;
      return q < 1.25f * 1.25f && q > 1.0f / (1.25f * 1.25f) ? Verdict::Agree : Verdict::Disagree;
    }
    const auto [lo0, hi0] = bounds(old);
    const auto [lo1, hi1] = bounds(now);
    return lo0 > hi1 || lo1 > hi0 ? Verdict::Disagree : Verdict::Unknown;
  }
};

}  // namespace

// One merge's frames as the row kernel and the whole-frame judgement read them.
struct BracketView {
  int n = 0, newest = 0, longest = 0;
  std::array<bool, kMaxBracket> usable{};
  std::array<const std::uint8_t*, kMaxBracket> pixels{};
  /// What the whole-frame check reads: the pixels, or where the pixel loop turns a frame itself,
  /// its check's grid turned here.
  std::array<const std::uint8_t*, kMaxBracket> judged{};
  std::array<float, kMaxBracket> scales{};
  const std::array<std::array<float, 256>, 3>* lut = nullptr;
  Judge judge{};
  float inv2s2 = 0;
  merge::RowKernel kernel = nullptr;  ///< the pixel loop (merge_kernel.h)
  /// merge::RowInput::nearLow and nearHigh, the whole frame.
  const std::uint8_t *nearLow = nullptr, *nearHigh = nullptr;

  void read(int i, std::size_t at, Reading& r) const {
    const std::uint8_t* p = judged[std::size_t(i)] + at;
    const auto& l = *lut;
    r.scale = scales[std::size_t(i)];
    r.e[0] = l[0][p[2]] * r.scale, r.e[1] = l[1][p[1]] * r.scale, r.e[2] = l[2][p[0]] * r.scale;
    r.code = std::max({p[0], p[1], p[2]});
    r.peak = std::max({r.e[0], r.e[1], r.e[2]});
  }
};

FrameConfidence BracketMerger::add(const Frame& in, Frame& out, Executor* executor) {
  MergeProjection frameOnly;
  return add(in, out, executor, frameOnly);
}

FrameConfidence BracketMerger::add(const Frame& in, Frame& out, Executor* executor,
                                   MergeProjection& projection) {
  const EquirectIntegrals* project = projection.integrals;
  if (project && (project->width != in.width || project->height != in.height))
    throw Error("a merge projects with the integrals of its frame's size (" +
                std::to_string(in.width) + "x" + std::to_string(in.height) + ", not " +
                std::to_string(project->width) + "x" + std::to_string(project->height) + ")");
  push(in);
  const int w = in.width, h = in.height;
  out.format = PanoramaFormat::RgbF32;
  out.width = w, out.height = h;
  out.bgr8.clear();
  const bool keep = projection.keepFrame || !project;
  if (keep)
    out.rgb.resize(std::size_t(w) * h * 3);
  else
    out.rgb.clear();
  out.sequence = in.sequence, out.timestamp = in.timestamp;
  out.captureTime = window_.front().captureTime;
  out.radianceScale = 1.0;
  out.exposure100us = in.exposure100us, out.gain = in.gain;
  int exposures = 0;
  BracketView view = prepare(alignedWindow(executor), exposures);
  const std::size_t pixels = std::size_t(w) * std::size_t(h);
  const bool fresh = previous_.size() == pixels;
  if (!fresh) {
    previous_.assign(pixels, 0.0f), reference_.assign(pixels, 0.0f);
    referenceIsPrevious_ = false;
    previousAway_ = referenceAway_ = false;
    previousKey_ = newKey(), referenceKey_ = newKey();
  }
  // Where the last merge was trusted, its luminance is the reference: this merge's goes into the
  // other buffer, and neither is copied.
  float* luminanceOut = referenceIsPrevious_ ? reference_.data() : previous_.data();
  const float* previous = previous_.data();
  const float* reference = referenceIsPrevious_ ? previous_.data() : reference_.data();
  // The last merges' luminance turned to the newest frame, where the camera turned since.
  std::uint64_t previousSequence = in.sequence;
  if (align_) {
    Alignment& a = *align_;
    if (fresh) previousSequence = a.previousSequence;
    const auto turn = [&](const float* lum, std::uint64_t then, std::vector<float>& into) {
      const glm::mat3 q = a.tracker.turnSince(then);
      if (align::displacementPixels(q, w) < kLeastTurnPixels) return lum;
      bringBack(lum == previous_.data(), lum == reference_.data());
      into.resize(pixels);
      align::turnLuminance(lum, w, h, q, into.data(), executor);
      return static_cast<const float*>(into.data());
    };
    previous = turn(previous, previousSequence, a.previousTurned);
    reference =
        referenceIsPrevious_ ? previous : turn(reference, a.referenceSequence, a.referenceTurned);
  }
  // Where older frames were turned (their readings a fraction of a pixel off), the newest frame's
  // neighbourhood.
  bool turned = false;
  for (int i = 0; i < view.newest; ++i)
    turned |= view.pixels[std::size_t(i)] != window_[std::size_t(i)].bgr8.data() ||
              (align_ && align_->byKernel[std::size_t(i)]);
  if (turned) {
    align_->nearLow.resize(pixels), align_->nearHigh.resize(pixels);
    align::neighbourhood(window_.back().bgr8.data(), w, h, align_->nearLow.data(),
                         align_->nearHigh.data(), executor);
    view.nearLow = align_->nearLow.data(), view.nearHigh = align_->nearHigh.data();
  }
  merge::FrameInput frame = frameInput(view, keep ? out.rgb.data() : nullptr,
                                       {previous, luminanceOut, reference}, fresh, project);
  // The luminance as some earlier merge wrote it (not turned since) keeps its key.
  frame.previousKey = previous == previous_.data() ? previousKey_ : 0;
  frame.referenceKey = reference == previous_.data()    ? previousKey_
                       : reference == reference_.data() ? referenceKey_
                                                        : 0;
  frame.luminanceKey = newKey();
  frame.luminanceBack = !(frameKernel_ && fetchLuminance_);
  frame.rgbKept = project && projection.keepWhereMerged && frameKernel_;
  MergeTally total;
  float* peaks = nullptr;
  if (project) {
    projection.rowPeaks.assign(std::size_t(h), 0.0f);
    peaks = projection.rowPeaks.data();
  }
  if (frameKernel_) {
    std::vector<merge::RowSums> rows(static_cast<std::size_t>(h));
    frameKernel_(frame, rows);
    for (std::size_t y = 0; y < std::size_t(h); ++y) {
      if (peaks) peaks[y] = rows[y].peak;
      total.add(tally(rows[y], y, project));
    }
  } else {
    total = parallelReduce(
        executor, std::size_t(h), Split{.grain = 1, .perThread = 4}, MergeTally{},
        [&](std::size_t y0, std::size_t y1) {
          MergeTally t;
          for (std::size_t y = y0; y < y1; ++y) {
            const merge::RowSums row = view.kernel(merge::RowInput::of(frame, y));
            if (peaks) peaks[y] = row.peak;
            t.add(tally(row, y, project));
          }
          return t;
        },
        [](MergeTally& into, const MergeTally& part) { into.add(part); });
  }
  if (project)
    for (int k = 0; k < kShCount; ++k) projection.coefficients.c[std::size_t(k)] = Rgb(total.sh[k]);
  FrameConfidence c = total.confidence(std::size_t(w) * h, exposures);
  // The strongest light read only by older frames (the newest clips it) is what the scene was
  // then: where the last merges found light contradicted (the scene moving), as much of it may
  // have moved since, unconfirmed.
  // (Frames left out whole, a hand over the lens, cast no doubt: they are not merged.)
  const double measured = c.agreement;
  if (!total.brightestFresh)
    for (int i = 0; i < view.newest; ++i)
      if (view.usable[std::size_t(i)])
        c.agreement = std::min(c.agreement, agreements_[std::size_t(i)]);
  agreements_.back() = measured;
  c.complete =
      int(window_.size()) == opt_.frames && exposures == opt_.frames &&
      std::all_of(view.usable.begin(), view.usable.begin() + view.n, [](bool u) { return u; });
  // This merge's luminance is away where the kernel kept it (FrameInput::luminanceBack).
  (luminanceOut == previous_.data() ? previousAway_ : referenceAway_) = !frame.luminanceBack;
  // A trusted merge (complete, its brightest pixel read unclipped, its confidence 0.9 or more)
  // is what later clipped pixels are measured against: the last one stays the reference.
  if (referenceIsPrevious_) {  // this merge's is the last
    std::swap(previous_, reference_);
    std::swap(previousAway_, referenceAway_);
    referenceKey_ = previousKey_;
  }
  previousKey_ = frame.luminanceKey;
  if (align_) {
    if (referenceIsPrevious_) align_->referenceSequence = previousSequence;
    align_->previousSequence = in.sequence;
  }
  referenceIsPrevious_ = c.complete && c.brightestMeasured && c.value() >= 0.9;
  return c;
}

BracketView BracketMerger::prepare(const std::array<const std::uint8_t*, kMaxBracket>& pixels,
                                   int& exposures) const {
  BracketView v;
  v.n = int(window_.size()), v.newest = v.n - 1;
  v.lut = &opt_.response.linear;
  const auto& lut = opt_.response.linear;
  v.judge = Judge{opt_.noiseFloor, opt_.clipLevel, lut[1][kWellExposed], lut[1][kSurelyUnclipped]};
  v.inv2s2 = float(1.0 / (2.0 * opt_.ghostSigma * opt_.ghostSigma));
  v.kernel = merge::active();
  for (int i = 0; i < v.n; ++i) {
    v.pixels[std::size_t(i)] = pixels[std::size_t(i)];
    v.judged[std::size_t(i)] = align_ && align_->byKernel[std::size_t(i)]
                                   ? align_->turned[std::size_t(i)].data()
                                   : pixels[std::size_t(i)];
    v.scales[std::size_t(i)] = float(window_[std::size_t(i)].radianceScale);
  }
  v.usable = usableFrames(v);
  v.longest = v.newest;
  std::vector<float> distinct;
  for (int i = 0; i < v.n; ++i) {
    if (!v.usable[std::size_t(i)]) continue;
    const float s = v.scales[std::size_t(i)];
    if (s < v.scales[std::size_t(v.longest)]) v.longest = i;
    // Exposures a quarter stop apart or less are one (a camera that rounds what was asked).
    if (std::none_of(distinct.begin(), distinct.end(),
                     [&](float d) { return std::abs(std::log2(d / s)) <= 0.25f; }))
      distinct.push_back(s);
  }
  exposures = int(distinct.size());
  return v;
}

merge::FrameInput BracketMerger::frameInput(const BracketView& v, float* rgb, const Luminance& lum,
                                            bool fresh, const EquirectIntegrals* project) const {
  merge::FrameInput in;
  // The usable frames, newest last (frames left out whole take no part).
  for (int i = 0; i < v.n; ++i) {
    if (!v.usable[std::size_t(i)]) continue;
    if (i == v.longest) in.longest = in.frames;
    const bool asTaken = v.pixels[std::size_t(i)] == window_[std::size_t(i)].bgr8.data();
    in.key[in.frames] = asTaken ? keys_[std::size_t(i)] : 0;
    if (const auto& q = align_ ? align_->byKernel[std::size_t(i)] : std::nullopt) {
      merge::FrameInput::Turn& t = in.turn[in.frames];
      t.apply = true;
      std::copy(&(*q)[0][0], &(*q)[0][0] + 9, t.q);
      const align::TurnGrid& g = align_->grids[std::size_t(i)];
      t.nodesX = g.nodesX, t.nodesY = g.nodesY, t.polar = g.polar;
      t.offset = g.offset.data(), t.row = g.row.data();
    }
    in.bgr[in.frames] = v.pixels[std::size_t(i)];
    in.scale[in.frames++] = v.scales[std::size_t(i)];
  }
  for (int c = 0; c < 3; ++c) in.lut[c] = (*v.lut)[std::size_t(c)].data();
  in.floor = v.judge.floor, in.clip = v.judge.clip, in.wellExposed = kWellExposed;
  in.wellLinear = v.judge.wellLinear, in.belowClipLinear = v.judge.belowClipLinear;
  in.inv2s2 = v.inv2s2;
  in.width = window_.back().width, in.height = window_.back().height;
  in.previous = lum.previous, in.luminance = lum.out, in.reference = lum.reference;
  in.fresh = fresh;
  in.nearLow = v.nearLow, in.nearHigh = v.nearHigh;
  in.rgb = rgb;
  if (align_) {
    for (int c = 0; c < 3; ++c)
      in.recode.table[c] = align_->coder.table(c),
      in.recode.inverseTop[c] = align_->coder.inverseTop(c);
    in.recode.first = align::Coder::kFirst, in.recode.last = align::Coder::kLast;
  }
  if (project)
    for (int k = 0; k < 5; ++k) in.col[k] = project->col[std::size_t(k)].data();
  return in;
}

MergeTally BracketMerger::tally(const merge::RowSums& s, std::size_t y,
                                const EquirectIntegrals* project) const {
  const float rw = rowWeight(int(y), window_.back().height, opt_.equirect);
  MergeTally t;
  if (project) {
    glm::dvec3 colSums[5];
    for (int k = 0; k < 5; ++k) colSums[k] = {s.col[k][0], s.col[k][1], s.col[k][2]};
    project->addRow(y, colSums, t.sh);
  }
  t.power = s.power * rw, t.clippedPower = s.clippedPower * rw, t.disagreedPower = s.lostPower * rw;
  t.clippedEstimate = s.clippedEstimate * rw;
  t.dark = s.dark;
  t.brightest = s.brightest, t.brightestClipped = s.brightestClipped;
  t.brightestFresh = s.brightestFresh;
  return t;
}

std::uint64_t BracketMerger::newKey() { return ++frameKeys; }

void BracketMerger::setFrameKernel(merge::FrameKernel kernel, bool turns,
                                   merge::LuminanceFetch fetch) {
  bringBack(true, true);  // what the kernel kept, before it goes
  frameKernel_ = std::move(kernel);
  kernelTurns_ = frameKernel_ && turns;
  fetchLuminance_ = frameKernel_ ? std::move(fetch) : merge::LuminanceFetch{};
}

void BracketMerger::bringBack(bool previous, bool reference) {
  const auto fetch = [&](bool& away, std::uint64_t key, std::vector<float>& into) {
    if (!away) return;
    if (!fetchLuminance_ || !fetchLuminance_(key, into.data()))
      throw Error("the bracket merge: the last merge's luminance is no longer where it was kept");
    away = false;
  };
  if (previous) fetch(previousAway_, previousKey_, previous_);
  if (reference) fetch(referenceAway_, referenceKey_, reference_);
}

std::array<bool, kMaxBracket> BracketMerger::usableFrames(const BracketView& v) const {
  // A whole frame that contradicts the newest on most of a sparse grid (a hand over the lens, a
  // flash) is left out; the newest frame always counts.
  std::array<bool, kMaxBracket> usable{};
  const int w = window_.back().width, h = window_.back().height;
  usable[std::size_t(v.newest)] = true;
  std::array<std::size_t, kMaxBracket> agree{}, disagree{};
  Reading now, old;
  for (int y = kCheckStep / 2; y < h; y += kCheckStep)
    for (int x = kCheckStep / 2; x < w; x += kCheckStep) {
      const std::size_t at = (std::size_t(y) * std::size_t(w) + std::size_t(x)) * 3;
      v.read(v.newest, at, now);
      for (int i = 0; i < v.newest; ++i) {
        v.read(i, at, old);
        const Verdict verdict = v.judge(old, now);
        agree[std::size_t(i)] += verdict == Verdict::Agree;
        disagree[std::size_t(i)] += verdict == Verdict::Disagree;
      }
    }
  const auto count = [](int n) { return std::size_t((n + kCheckStep / 2 - 1) / kCheckStep); };
  const std::size_t grid = count(h) * count(w);
  for (int i = 0; i < v.newest; ++i) {
    const std::size_t decided = agree[std::size_t(i)] + disagree[std::size_t(i)];
    usable[std::size_t(i)] = decided * 100 < grid || disagree[std::size_t(i)] * 2 <= decided;
  }
  return usable;
}

}  // namespace lp
