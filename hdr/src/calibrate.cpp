#include "liveprobe/hdr/calibrate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/core.hpp>

#include "liveprobe/sh/error.h"

namespace lp {

namespace {

// One pair of codes that some pixels read in a pair of frames: g(a) - g(b) = r.
struct CodePair {
  std::uint8_t a, b;
  std::uint32_t pixels;
  double r;  ///< log(t_i / t_j)
};

// Per frame, the pixels whose colour is their own: those whose chroma block reads one colour (every
// channel within kFlatBlock codes). Every pixel where the camera sends each pixel's colour.
constexpr int kFlatBlock = 1;
constexpr int kShadedEnd = 3;
std::vector<std::vector<std::uint8_t>> ownColour(const std::vector<Frame>& frames,
                                                 ChromaBlock chroma) {
  std::vector<std::vector<std::uint8_t>> own;
  for (const Frame& f : frames) {
    std::vector<std::uint8_t> m(std::size_t(f.width) * std::size_t(f.height), 1);
    if (chroma.width > 1 || chroma.height > 1)
      for (int by = 0; by + chroma.height <= f.height; by += chroma.height)
        for (int bx = 0; bx + chroma.width <= f.width; bx += chroma.width) {
          std::array<int, 3> lo{255, 255, 255}, hi{0, 0, 0};
          for (int y = by; y < by + chroma.height; ++y)
            for (int x = bx; x < bx + chroma.width; ++x)
              for (int c = 0; c < 3; ++c) {
                const int v = f.bgr8[(std::size_t(y) * std::size_t(f.width) + std::size_t(x)) * 3 +
                                     std::size_t(c)];
                lo[std::size_t(c)] = std::min(lo[std::size_t(c)], v);
                hi[std::size_t(c)] = std::max(hi[std::size_t(c)], v);
              }
          bool flat = true;
          for (int c = 0; c < 3; ++c)
            flat = flat && hi[std::size_t(c)] - lo[std::size_t(c)] <= kFlatBlock &&
                   lo[std::size_t(c)] > kShadedEnd && hi[std::size_t(c)] < 255 - kShadedEnd;
          for (int y = by; y < by + chroma.height; ++y)
            for (int x = bx; x < bx + chroma.width; ++x)
              m[std::size_t(y) * std::size_t(f.width) + std::size_t(x)] = flat;
        }
    own.push_back(std::move(m));
  }
  return own;
}

// Every pair of codes (both within (0, 255)) that one channel's pixels read in every pair of
// frames of distinct exposures, from their joint histograms: built once, solved three times.
std::vector<CodePair> codePairs(const std::vector<Frame>& frames,
                                const std::vector<std::vector<std::uint8_t>>& own, int channel) {
  std::vector<CodePair> pairs;
  std::vector<std::uint32_t> joint(256 * 256);
  for (std::size_t i = 0; i < frames.size(); ++i)
    for (std::size_t j = i + 1; j < frames.size(); ++j) {
      const double r = std::log(frames[j].radianceScale / frames[i].radianceScale);
      if (std::abs(r) < 0.02) continue;  // the same exposure: says nothing
      std::fill(joint.begin(), joint.end(), 0u);
      const auto& p = frames[i].bgr8;
      const auto& q = frames[j].bgr8;
      for (std::size_t k = std::size_t(2 - channel); k < p.size(); k += 3)
        if (own[i][k / 3] && own[j][k / 3] && p[k] > 0 && p[k] < 255 && q[k] > 0 && q[k] < 255)
          ++joint[p[k] * 256u + q[k]];
      for (int a = 1; a < 255; ++a)
        for (int b = 1; b < 255; ++b)
          if (const std::uint32_t n = joint[std::size_t(a * 256 + b)])
            pairs.push_back({std::uint8_t(a), std::uint8_t(b), n, r});
    }
  return pairs;
}

// One channel's log response g(z) = log(linear(z)) from the codes pixels took in pairs of frames:
// where a pixel reads a in a frame of exposure t_i and b in one of t_j, both within (0, 255),
// g(a) - g(b) = log(t_i / t_j) (comparametric: Mann and Picard; Grossberg and Nayar). Every
// pixel of every pair of frames goes into joint histograms; each pair of codes seen is one
// equation (a thousand pixels of one uniform wall are one reading of the curve, not a thousand),
// weighed by the two codes' quantisation noise in log units, g'(z)^2 / 12, so that a coarse code
// pulls little on the finer codes it pairs with, and, given the last solve (`last`), robustly
// (Huber): a pair that chroma subsampling or compression made up pulls little. `noise` comes from
// the last solve. A smoothness in the log of the code, under which any power law is free, carries
// the curve over codes no pair reads; g(128) = 0. `support` gets the pixels that read each code
// in some pair.
std::array<double, 256> solveChannel(const std::vector<CodePair>& pairs,
                                     const std::array<double, 256>& noise,
                                     const std::array<double, 256>* last,
                                     std::array<std::size_t, 256>& support) {
  cv::Mat A = cv::Mat::zeros(256, 256, CV_64F), rhs = cv::Mat::zeros(256, 1, CV_64F);
  support.fill(0);
  double total = 0;
  for (const CodePair& c : pairs) {
    const int a = c.a, b = c.b;
    const double r = c.r;
    const double var = noise[std::size_t(a)] + noise[std::size_t(b)];
    double w = 1.0 / var;
    if (last) {  // Huber: beyond two sigmas of the last solve, the weight falls as 1 / error
      const double e = std::abs((*last)[std::size_t(a)] - (*last)[std::size_t(b)] - r);
      const double k = 2.0 * std::sqrt(var);
      if (e > k) w *= k / e;
    }
    A.at<double>(a, a) += w, A.at<double>(b, b) += w;
    A.at<double>(a, b) -= w, A.at<double>(b, a) -= w;
    rhs.at<double>(a) += w * r, rhs.at<double>(b) -= w * r;
    support[std::size_t(a)] += c.pixels, support[std::size_t(b)] += c.pixels;
    total += 2 * w;
  }
  // The second difference of g over log z, per unit of log z, each code weighing ten times the
  // average code's data (measured on sky, quarry and sunset scenes through sRGB, gamma 1.8 and
  // 2.6 responses: weaker lets 8-bit steps through at the darkest codes, much stronger bends the
  // sRGB toe). Codes 1 and 254 continue straight to 0 and 255.
  const double smooth = 10.0 * total / 254;
  const auto add = [&](int z, const double(&w)[3]) {
    for (int u = 0; u < 3; ++u)
      for (int v = 0; v < 3; ++v) A.at<double>(z - 1 + u, z - 1 + v) += smooth * w[u] * w[v];
  };
  for (int z = 2; z < 254; ++z) {
    const double h0 = std::log(double(z) / (z - 1)), h1 = std::log(double(z + 1) / z);
    const double mean = 0.5 * (h0 + h1);
    add(z, {mean / h0, -mean * (1 / h0 + 1 / h1), mean / h1});
  }
  add(1, {1, -2, 1}), add(254, {1, -2, 1});
  A.at<double>(128, 128) += 1e6 * smooth;  // g(128) = 0
  cv::Mat g;
  if (!cv::solve(A, rhs, g, cv::DECOMP_CHOLESKY))
    throw Error("the response cannot be solved from these frames");
  std::array<double, 256> out{};
  for (int z = 0; z < 256; ++z) out[std::size_t(z)] = g.at<double>(z);
  return out;
}

// The largest fall (in log units: 10%) a recovered curve may show and still be noise: YUYV's and
// MJPEG's shared chroma leave up to 6% at the brightest codes of a still scene; a scene that
// changed during the sweep leaves more (HdrMerge.TheResponseRecoveredFromASweepIsThePowerLaw).
constexpr double kLargestFall = 0.10;

std::string formatPercent(double logRatio) {
  char text[16];
  std::snprintf(text, sizeof text, "%.0f%%", 100.0 * (1.0 - std::exp(-logRatio)));
  return text;
}

// The rising curve nearest to `curve` in weighted least squares (pool adjacent violators): each
// run of codes that falls becomes its weighted mean. Weights: 1 plus the pixels that read a code.
void risingFit(std::array<double, 256>& curve, const std::array<std::size_t, 256>& support) {
  struct Block {
    double sum, weight;
    int first, last;
  };
  std::vector<Block> blocks;
  for (int z = 0; z < 256; ++z) {
    const double w = 1.0 + double(support[std::size_t(z)]);
    blocks.push_back({w * curve[std::size_t(z)], w, z, z});
    while (blocks.size() > 1 && blocks[blocks.size() - 2].sum / blocks[blocks.size() - 2].weight >
                                    blocks.back().sum / blocks.back().weight) {
      const Block top = blocks.back();
      blocks.pop_back();
      blocks.back().sum += top.sum, blocks.back().weight += top.weight;
      blocks.back().last = top.last;
    }
  }
  for (const Block& b : blocks)
    for (int z = b.first; z <= b.last; ++z) curve[std::size_t(z)] = b.sum / b.weight;
}

}  // namespace

int darkestCode(const Frame& frame) {
  std::array<std::size_t, 256> histogram{};
  for (const std::uint8_t v : frame.bgr8) ++histogram[v];
  std::size_t seen = 0;
  for (int z = 0; z < 256; ++z)
    if ((seen += histogram[std::size_t(z)]) * 2000 >= frame.bgr8.size()) return z;
  return 255;
}

CameraResponse calibrateResponse(const std::vector<Frame>& frames, ChromaBlock chroma) {
  std::vector<double> distinct;
  for (const Frame& f : frames) {
    if (f.format != PanoramaFormat::BgrU8) throw Error("calibration takes 8-bit frames");
    if (f.width != frames.front().width || f.height != frames.front().height)
      throw Error("calibration frames differ in size");
    const double t = 1.0 / f.radianceScale;
    if (std::none_of(distinct.begin(), distinct.end(),
                     [&](double d) { return std::abs(d - t) <= 0.02 * t; }))
      distinct.push_back(t);
  }
  if (distinct.size() < 3)
    throw Error("calibration needs frames at 3 or more exposure times; got " +
                std::to_string(distinct.size()));
  const auto own = ownColour(frames, chroma);
  std::array<std::array<double, 256>, 3> g{};
  std::array<std::array<std::size_t, 256>, 3> support{};
  for (int c = 0; c < 3; ++c) {
    // Each equation weighs by its codes' quantisation noise in log units, (g'(z))^2 / 12: a code
    // that spans a wide range of light pulls little on the finer codes it is paired with. The
    // slope comes from the last solve, starting from a gamma of 2.2.
    std::array<double, 256> noise{};
    for (int z = 0; z < 256; ++z) noise[std::size_t(z)] = std::pow(2.2 / std::max(z, 1), 2) / 12;
    const std::vector<CodePair> pairs = codePairs(frames, own, c);
    for (int pass = 0; pass < 3; ++pass) {
      const std::array<double, 256> last = g[std::size_t(c)];
      g[std::size_t(c)] =
          solveChannel(pairs, noise, pass ? &last : nullptr, support[std::size_t(c)]);
      for (int z = 1; z < 255; ++z) {
        const double slope = std::max(1e-4, 0.5 * (g[std::size_t(c)][std::size_t(z + 1)] -
                                                   g[std::size_t(c)][std::size_t(z - 1)]));
        noise[std::size_t(z)] = slope * slope / 12;
      }
    }
  }
  // 8-bit steps and compression noise (JPEG's chroma) leave small falls in a curve that must
  // rise: the least-squares rising curve (pool adjacent violators, weighed by the pixels each
  // code's readings hold) replaces it. A larger fall is no noise: the scene moved, or has too
  // few tones.
  for (int c = 0; c < 3; ++c) {
    auto& curve = g[std::size_t(c)];
    for (int a = 1; a < 255; ++a)
      for (int b = a + 1; b < 255; ++b)
        if (curve[std::size_t(a)] - curve[std::size_t(b)] > kLargestFall)
          throw Error(std::string("the recovered response falls by ") +
                      formatPercent(curve[std::size_t(a)] - curve[std::size_t(b)]) + " from code " +
                      std::to_string(a) + " to " + std::to_string(b) + " in channel " + "RGB"[c] +
                      ": the scene needs more tones, or it moved during the sweep");
    risingFit(curve, support[std::size_t(c)]);
  }
  CameraResponse r;
  r.name = "calibrated";
  // The curve is known up to one scale (each channel is 1 at code 128: equal codes are grey).
  // The clip is where green's power law over the well-determined codes reaches code 255: the
  // very top codes are the least constrained by the solve.
  const PowerLaw fit = fitPowerLaw([&](int i) { return std::exp(g[1][std::size_t(i)]); });
  const double norm = fit.atClip;
  if (!(norm > 0) || !std::isfinite(norm)) throw Error("the recovered response is not positive");
  for (int i = 0; i < 256; ++i)
    for (int c = 0; c < 3; ++c)
      r.linear[std::size_t(c)][std::size_t(i)] =
          float(std::exp(g[std::size_t(c)][std::size_t(i)]) / norm);
  // From the darkest to the brightest code every channel read (codes between that no pair read
  // follow the curve's shape); 0 and 255 are never read: they are the ends.
  r.readFrom = 0, r.readTo = 255;
  for (const auto& ch : support) {
    int lo = 1, hi = 254;
    while (lo < 254 && ch[std::size_t(lo)] == 0) ++lo;
    while (hi > lo && ch[std::size_t(hi)] == 0) --hi;
    r.readFrom = std::max(r.readFrom, lo == 1 ? 0 : lo);
    r.readTo = std::min(r.readTo, hi == 254 ? 255 : hi);
  }
  if (r.readTo - r.readFrom < 64)
    throw Error("the frames read only codes " + std::to_string(r.readFrom) + " to " +
                std::to_string(r.readTo) + " in every channel: the scene needs more tones");
  return r;
}

Sweep sweepExposures(FrameSource& camera, ExposureControl& control, const SweepOptions& o) {
  const std::pair<std::int32_t, std::int32_t> range = control.exposureRange();
  const std::int32_t least = range.first, most = range.second;  // captured: no bindings
  Sweep sweep;
  std::vector<double> brightness;
  std::vector<int> delays;
  std::int32_t previous = -1;
  const auto meanCode = [](const Frame& f) {
    double sum = 0;
    for (const std::uint8_t v : f.bgr8) sum += v;
    return sum / double(std::max<std::size_t>(1, f.bgr8.size()));
  };
  const auto say = [&](const std::string& line) {
    if (o.onStop) o.onStop(line);
  };
  const auto take = [&](int stop) {
    const std::int32_t asked =
        std::clamp(std::int32_t(std::lround(double(o.locked) * std::exp2(stop))), least, most);
    if (asked == previous) return false;  // clamped to the control's limit: already taken
    previous = asked;
    if (o.stopRequested && o.stopRequested()) return sweep.stopped = true, false;
    control.requestExposure(asked);
    Frame f;
    const double before = brightness.empty() ? -1.0 : brightness.back();
    bool seen = false;
    for (int i = 0; i < o.settle; ++i) {
      if (!camera.next(f)) throw Error(o.name + ": the stream ended");
      if (f.exposureReported) {
        if (std::lround(1e4 / f.radianceScale) != asked) continue;
        delays.push_back(i);
        break;
      }
      const double m = meanCode(f);
      if (!seen && before >= 0 && std::abs(m - before) > std::max(1.0, 0.04 * before))
        delays.push_back(i), seen = true;
    }
    if (!f.exposureReported) f.radianceScale = 1e4 / asked, f.exposure100us = asked;
    const int reported = int(std::lround(1e4 / f.radianceScale));
    char line[160];
    if (f.exposureReported && !sweep.frames.empty() &&
        reported == int(std::lround(1e4 / sweep.frames.back().radianceScale))) {
      std::snprintf(line, sizeof line,
                    "  %+d EV: %d x 100 us, the camera's limit (as the stop before): not counted",
                    stop, reported);
      say(line);
      return false;
    }
    brightness.push_back(meanCode(f));
    std::snprintf(line, sizeof line, "  %+d EV: %d x 100 us, mean code %.1f", stop, reported,
                  brightness.back());
    say(line);
    sweep.frames.push_back(std::move(f));
    return true;
  };
  for (int stop = o.lowest; stop <= o.highest && !sweep.stopped; ++stop) take(stop);
  std::size_t shortest = 0;  // frames[0] is the lowest stop, then each one taken below it
  for (int stop = o.lowest - 1; stop >= o.lowest - 12 && !sweep.frames.empty() && !sweep.stopped;
       --stop) {
    if (darkestCode(sweep.frames[shortest]) <= kDarkestCode || !take(stop)) break;
    shortest = sweep.frames.size() - 1;
  }
  if (sweep.stopped) return sweep;
  // A camera that takes the control but not the exposure shows one brightness at every stop.
  const auto [lo, hi] = std::minmax_element(brightness.begin(), brightness.end());
  if (sweep.frames.size() < 3 || *hi - *lo < 8.0) {
    char range[64];
    std::snprintf(range, sizeof range, "%.3g to %.3g", brightness.empty() ? 0.0 : *lo,
                  brightness.empty() ? 0.0 : *hi);
    throw Error(o.name + ": the camera ignores its exposure control (mean code " + range +
                " across the sweep)");
  }
  if (!delays.empty()) {  // the most common delay over the stops that showed one
    std::map<int, int> count;
    for (const int d : delays) ++count[d];
    sweep.controlDelay = std::max_element(count.begin(), count.end(), [](auto& a, auto& b) {
                           return a.second < b.second;
                         })->first;
  }
  return sweep;
}

}  // namespace lp
