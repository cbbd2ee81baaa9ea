#include "liveprobe/capture/ball.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "liveprobe/frame/srgb.h"

namespace lp {

namespace {

/// The frame as grey in [0, 1] (float, so the rim's sub-pixel position is not lost to 8-bit
/// steps): an 8-bit frame's luma, a float frame's luminance exposed so its 99th percentile is
/// white and encoded as sRGB.
cv::Mat greyOf(const Frame& f) {
  cv::Mat grey;
  if (f.format == PanoramaFormat::BgrU8) {
    const cv::Mat bgr(f.height, f.width, CV_8UC3, const_cast<std::uint8_t*>(f.bgr8.data()));
    cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
    grey.convertTo(grey, CV_32F, 1.0 / 255);
    return grey;
  }
  std::vector<float> lum(std::size_t(f.width) * std::size_t(f.height));
  for (std::size_t i = 0; i < lum.size(); ++i)
    lum[i] = 0.2126f * f.rgb[3 * i] + 0.7152f * f.rgb[3 * i + 1] + 0.0722f * f.rgb[3 * i + 2];
  std::vector<float> sorted = lum;
  const std::size_t at = sorted.size() * 99 / 100;
  std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(at), sorted.end());
  const float white = std::max(sorted[at], 1e-12f);
  grey.create(f.height, f.width, CV_32F);
  auto* g = grey.ptr<float>();
  for (std::size_t i = 0; i < lum.size(); ++i)
    g[i] = linearToSrgb(std::clamp(lum[i] / white, 0.0f, 1.0f));
  return grey;
}

/// The circle through `pts` by least squares (Kasa: x^2 + y^2 + D x + E y + F = 0).
std::optional<cv::Vec3d> fitCircle(const std::vector<cv::Point2d>& pts) {
  if (pts.size() < 3) return std::nullopt;
  cv::Mat A(int(pts.size()), 3, CV_64F), b(int(pts.size()), 1, CV_64F);
  for (int i = 0; i < int(pts.size()); ++i) {
    A.at<double>(i, 0) = pts[std::size_t(i)].x;
    A.at<double>(i, 1) = pts[std::size_t(i)].y;
    A.at<double>(i, 2) = 1.0;
    b.at<double>(i, 0) = -(pts[std::size_t(i)].x * pts[std::size_t(i)].x +
                           pts[std::size_t(i)].y * pts[std::size_t(i)].y);
  }
  cv::Mat s;
  if (!cv::solve(A, b, s, cv::DECOMP_SVD)) return std::nullopt;
  const double cx = -s.at<double>(0) / 2, cy = -s.at<double>(1) / 2;
  const double r2 = cx * cx + cy * cy - s.at<double>(2);
  if (!(r2 > 0)) return std::nullopt;
  return cv::Vec3d(cx, cy, std::sqrt(r2));
}

/// The circle most of `pts` lie within 1.5 pixels of, from 300 triples (a fixed seed: the same
/// frame gives the same circle). Interior reflections (a railing's arcs) give strong edges near the
/// rim too, and least squares alone would follow them.
std::optional<cv::Vec3d> ransacCircle(const std::vector<cv::Point2d>& pts) {
  if (pts.size() < 3) return std::nullopt;
  cv::RNG rng(0x1234);
  std::optional<cv::Vec3d> best;
  std::size_t bestCount = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const auto a = std::size_t(rng.uniform(0, int(pts.size())));
    const auto b = std::size_t(rng.uniform(0, int(pts.size())));
    const auto c = std::size_t(rng.uniform(0, int(pts.size())));
    if (a == b || b == c || a == c) continue;
    const auto fit = fitCircle({pts[a], pts[b], pts[c]});
    if (!fit) continue;
    std::size_t count = 0;
    for (const auto& p : pts)
      count += std::abs(std::hypot(p.x - (*fit)[0], p.y - (*fit)[1]) - (*fit)[2]) < 1.5;
    if (count > bestCount) bestCount = count, best = fit;
  }
  return best;
}

/// The circle through the rim's strongest radial edge: along 360 rays out of the rough circle's
/// centre (OpenCV pixel coordinates), the strongest radial gradient within `band` pixels of its
/// radius, to sub-pixel by a parabola through its neighbours; the circle most of those points
/// agree with (ransacCircle), then fitted to them by least squares, the far ones dropped. None when
/// fewer than `minPoints` rays keep a point (within a wide band, an interior reflection's edge can
/// be stronger than the rim's on most rays).
std::optional<cv::Vec3d> edgeCircle(const cv::Mat& grey, cv::Vec3d rough, double band,
                                    std::size_t minPoints) {
  cv::Mat smooth, gx, gy;
  cv::GaussianBlur(grey, smooth, cv::Size(0, 0), 1.2);
  cv::Sobel(smooth, gx, CV_32F, 1, 0, 3);
  cv::Sobel(smooth, gy, CV_32F, 0, 1, 3);
  const auto at = [](const cv::Mat& m, double x, double y) {  // bilinear, (x, y) inside
    const int x0 = int(x), y0 = int(y);
    const double fx = x - x0, fy = y - y0;
    const float* r0 = m.ptr<float>(y0) + x0;
    const float* r1 = m.ptr<float>(y0 + 1) + x0;
    return (1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) + fy * ((1 - fx) * r1[0] + fx * r1[1]);
  };
  std::vector<cv::Point2d> pts;
  constexpr double kStep = 0.25;
  for (int a = 0; a < 360; ++a) {
    const double c = std::cos(a * CV_PI / 180), s = std::sin(a * CV_PI / 180);
    std::vector<double> g;
    const double r0 = rough[2] - band, r1 = rough[2] + band;
    for (double r = r0; r <= r1; r += kStep) {
      const double x = rough[0] + r * c, y = rough[1] + r * s;
      const bool inside = x >= 2 && y >= 2 && x <= grey.cols - 3 && y <= grey.rows - 3;
      g.push_back(inside ? std::abs(at(gx, x, y) * c + at(gy, x, y) * s) : 0.0);
    }
    const auto peak = std::max_element(g.begin(), g.end());
    const std::size_t k = std::size_t(peak - g.begin());
    if (*peak <= 0 || k == 0 || k + 1 >= g.size()) continue;
    const double den = g[k - 1] - 2 * g[k] + g[k + 1];
    const double offset = den < 0 ? 0.5 * (g[k - 1] - g[k + 1]) / den : 0.0;
    const double r = r0 + (double(k) + offset) * kStep;
    pts.emplace_back(rough[0] + r * c, rough[1] + r * s);
  }
  std::optional<cv::Vec3d> fit = ransacCircle(pts);
  for (int round = 0; fit && round < 3; ++round) {
    std::vector<cv::Point2d> kept;
    for (const auto& p : pts)
      if (std::abs(std::hypot(p.x - (*fit)[0], p.y - (*fit)[1]) - (*fit)[2]) < 2.0)
        kept.push_back(p);
    pts = std::move(kept);
    fit = fitCircle(pts);
  }
  if (!fit || pts.size() < minPoints) return std::nullopt;
  return fit;
}

/// The frame's luminance in linear light, scaled so its 99th percentile is 1 and clamped at 4
/// (a sun in the ball's reflection would outweigh the rim's step): the rim's model is a step in
/// radiance.
cv::Mat linearOf(const Frame& f) {
  const std::size_t n = std::size_t(f.width) * std::size_t(f.height);
  std::vector<float> lum(n);
  if (f.format == PanoramaFormat::BgrU8) {
    float table[256];
    for (int i = 0; i < 256; ++i) table[i] = srgbToLinear(float(i) / 255.0f);
    for (std::size_t i = 0; i < n; ++i)
      lum[i] = 0.0722f * table[f.bgr8[3 * i]] + 0.7152f * table[f.bgr8[3 * i + 1]] +
               0.2126f * table[f.bgr8[3 * i + 2]];
  } else {
    for (std::size_t i = 0; i < n; ++i)
      lum[i] = 0.2126f * f.rgb[3 * i] + 0.7152f * f.rgb[3 * i + 1] + 0.0722f * f.rgb[3 * i + 2];
  }
  std::vector<float> sorted = lum;
  const std::size_t at = n * 99 / 100;
  std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(at), sorted.end());
  const float white = std::max(sorted[at], 1e-12f);
  cv::Mat out(f.height, f.width, CV_32F);
  auto* o = out.ptr<float>();
  for (std::size_t i = 0; i < n; ++i) o[i] = std::min(lum[i] / white, 4.0f);
  return out;
}

// The rim's model, along a ray at radius r with the rim at E. Inside, the ball reflects the
// directions around the one straight behind it, at an angle from it of about
// 2 sqrt(2 (E - r) / R): a smooth scene there reads a + b sqrt(E - r) + c (E - r) + d (E - r)^1.5.
// Outside, the scene itself: f + g (r - E) + h (r - E)^2. All of it seen through the camera's
// blur, a Gaussian whose width is fitted too.
constexpr int kTerms = 7;
constexpr double kReach = 6.0;   ///< profile: radii within this of the circle's
constexpr double kSearch = 3.0;  ///< the rim's edge sought within this of the circle's radius
constexpr double kTable = 0.01;  ///< the basis tables' step in r - E
constexpr double kSigmas[] = {0.35, 0.5, 0.7, 1.0, 1.4, 2.0};
constexpr double kMaxRimResidual = 0.5;  ///< pixels RMS: a circle the rim's edges do not hold

/// The blurred basis as a function of r - E, tabulated once per blur.
struct RimBasis {
  double lo = 0;
  std::vector<std::array<double, kTerms>> at;  ///< at[(d - lo) / kTable]
  explicit RimBasis(double sigma) {
    constexpr int kTaps = 25;  // +-3 sigma: coarser taps bias the edge by a tenth of a pixel
    double tap[kTaps], w[kTaps], sum = 0;
    for (int t = 0; t < kTaps; ++t) {
      tap[t] = sigma * (t - (kTaps - 1) / 2) * 0.25;
      w[t] = std::exp(-0.5 * tap[t] * tap[t] / (sigma * sigma));
      sum += w[t];
    }
    const double reach = kReach + kSearch + 0.1;
    lo = -reach;
    const int n = int(std::ceil(2 * reach / kTable)) + 1;
    at.resize(std::size_t(n));
    for (int i = 0; i < n; ++i) {
      std::array<double, kTerms> b{};
      for (int t = 0; t < kTaps; ++t) {
        const double d = lo + i * kTable + tap[t], wt = w[t] / sum;
        if (d < 0) {
          const double q = std::sqrt(-d);
          b[0] += wt, b[1] += wt * q, b[2] += wt * q * q, b[3] += wt * q * q * q;
        } else {
          b[4] += wt, b[5] += wt * d, b[6] += wt * d * d;
        }
      }
      at[std::size_t(i)] = b;
    }
  }
  const std::array<double, kTerms>& operator()(double d) const {
    const long i = std::lround((d - lo) / kTable);
    return at[std::size_t(std::clamp(i, 0L, long(at.size()) - 1))];
  }
};

/// The model's least-squares residual for the rim at `edge`, of profile `p` sampled at `at`.
double rimResidual(const RimBasis& basis, const std::vector<double>& at,
                   const std::vector<double>& p, double edge) {
  cv::Matx<double, kTerms, kTerms> ata = cv::Matx<double, kTerms, kTerms>::zeros();
  cv::Vec<double, kTerms> atb = cv::Vec<double, kTerms>::all(0);
  double pp = 0;
  for (std::size_t i = 0; i < at.size(); ++i) {
    const auto& b = basis(at[i] - edge);
    for (int j = 0; j < kTerms; ++j) {
      atb[j] += b[std::size_t(j)] * p[i];
      for (int k = j; k < kTerms; ++k) ata(j, k) += b[std::size_t(j)] * b[std::size_t(k)];
    }
    pp += p[i] * p[i];
  }
  for (int j = 0; j < kTerms; ++j)
    for (int k = 0; k < j; ++k) ata(j, k) = ata(k, j);
  cv::Vec<double, kTerms> x;
  if (!cv::solve(ata, atb, x, cv::DECOMP_SVD)) return HUGE_VAL;
  return pp - x.dot(atb);
}

/// The rim's radius in one profile (radii `at` about `radius`): the edge whose model leaves the
/// least residual, scanned at a tenth of a pixel, then a hundredth, then a parabola through the
/// best and its neighbours; `residual` gets it.
double rimEdge(const RimBasis& basis, const std::vector<double>& at, const std::vector<double>& p,
               double radius, double& residual) {
  double best = radius, bestErr = HUGE_VAL;
  for (double e = radius - kSearch; e <= radius + kSearch + 1e-9; e += 0.1) {
    const double err = rimResidual(basis, at, p, e);
    if (err < bestErr) bestErr = err, best = e;
  }
  const double coarse = best;
  double errs[21];
  for (int k = 0; k <= 20; ++k) {
    const double e = coarse + (k - 10) * 0.01;
    errs[k] = rimResidual(basis, at, p, e);
    if (errs[k] <= bestErr) bestErr = errs[k], best = e;
  }
  const int k = int(std::lround((best - coarse) / 0.01)) + 10;
  if (k > 0 && k < 20) {
    const double den = errs[k - 1] - 2 * errs[k] + errs[k + 1];
    if (den > 0) best += 0.5 * 0.01 * (errs[k - 1] - errs[k + 1]) / den;
  }
  residual = bestErr;
  return best;
}

/// The circle refined from one within about two pixels (OpenCV pixel coordinates) by the rim's
/// model: 32 sectors' mean radial profiles (16 rays each, bilinear), each sector's edge
/// (rimEdge), the blur the one that fits all sectors best, and the circle fitted to the 32 edges,
/// the sectors that disagree (a stand, a highlight) dropped; three times, the profiles taken
/// about the new centre.
/// `blur`, where given: the blur a fit of the same camera's rim found (BallCircle::rimBlur), the
/// only one tried.
std::optional<BallCircle> fitRim(const cv::Mat& lin, cv::Vec3d c, double blur = 0) {
  constexpr int kSectors = 32, kRays = 16;
  constexpr double kStep = 0.25;
  static const std::vector<RimBasis> bases = [] {
    std::vector<RimBasis> b;
    for (const double s : kSigmas) b.emplace_back(s);
    return b;
  }();
  std::vector<cv::Point2d> kept;
  double sigma = 0;
  for (int round = 0; round < 3; ++round) {
    std::vector<double> at;
    for (double r = c[2] - kReach; r <= c[2] + kReach + 1e-9; r += kStep) at.push_back(r);
    std::vector<std::vector<double>> profiles(kSectors);
    for (int k = 0; k < kSectors; ++k) {
      std::vector<double> p(at.size(), 0.0);
      bool whole = true;
      for (int j = 0; j < kRays && whole; ++j) {
        const double a = 2 * CV_PI * (k + (j + 0.5) / kRays) / kSectors;
        const double cs = std::cos(a), sn = std::sin(a);
        for (std::size_t i = 0; i < at.size() && whole; ++i) {
          const double x = c[0] + at[i] * cs, y = c[1] + at[i] * sn;
          whole = x >= 0 && y >= 0 && x < lin.cols - 1 && y < lin.rows - 1;
          if (!whole) break;
          const int x0 = int(x), y0 = int(y);
          const double fx = x - x0, fy = y - y0;
          const float* r0 = lin.ptr<float>(y0) + x0;
          const float* r1 = lin.ptr<float>(y0 + 1) + x0;
          p[i] += ((1 - fx) * (1 - fy) * r0[0] + fx * (1 - fy) * r0[1] + (1 - fx) * fy * r1[0] +
                   fx * fy * r1[1]) /
                  kRays;
        }
      }
      if (whole) profiles[std::size_t(k)] = std::move(p);  // (a sector past the frame's edge: none)
    }
    double bestTotal = HUGE_VAL;
    std::vector<cv::Point2d> edges;
    for (std::size_t b = 0; b < bases.size(); ++b) {
      if (blur > 0 && kSigmas[b] != blur) continue;
      const RimBasis& basis = bases[b];
      double total = 0;
      std::vector<cv::Point2d> pts;
      for (int k = 0; k < kSectors; ++k) {
        const auto& p = profiles[std::size_t(k)];
        if (p.empty()) continue;
        double residual = 0;
        const double e = rimEdge(basis, at, p, c[2], residual);
        total += residual;
        const double a = 2 * CV_PI * (k + 0.5) / kSectors;
        pts.emplace_back(c[0] + e * std::cos(a), c[1] + e * std::sin(a));
      }
      if (total < bestTotal) bestTotal = total, edges = std::move(pts), sigma = kSigmas[b];
    }
    if (edges.size() < kSectors / 2) return std::nullopt;
    auto fit = fitCircle(edges);
    kept = edges;
    for (int drop = 0; fit && drop < 2; ++drop) {
      std::vector<double> d;
      for (const auto& q : kept)
        d.push_back(std::abs(std::hypot(q.x - (*fit)[0], q.y - (*fit)[1]) - (*fit)[2]));
      std::vector<double> sorted = d;
      std::nth_element(sorted.begin(), sorted.begin() + long(sorted.size() / 2), sorted.end());
      const double limit = std::max(0.1, 3.0 * sorted[sorted.size() / 2]);
      std::vector<cv::Point2d> within;
      for (std::size_t i = 0; i < kept.size(); ++i)
        if (d[i] <= limit) within.push_back(kept[i]);
      if (within.size() < kSectors / 2) break;
      kept = std::move(within);
      fit = fitCircle(kept);
    }
    if (!fit || std::hypot((*fit)[0] - c[0], (*fit)[1] - c[1]) > kSearch) return std::nullopt;
    c = *fit;
  }
  double sum = 0;
  for (const auto& q : kept) {
    const double d = std::hypot(q.x - c[0], q.y - c[1]) - c[2];
    sum += d * d;
  }
  // OpenCV's pixel centres are whole numbers; liveprobe's are at +0.5.
  return BallCircle{c[0] + 0.5,       c[1] + 0.5, c[2], std::sqrt(sum / double(kept.size())),
                    int(kept.size()), sigma};
}

/// The part of `frame` in `window` (within it).
Frame cropOf(const Frame& f, const FrameWindow& window) {
  const auto [x0, y0, w, h] = window;
  Frame c;
  c.width = w, c.height = h, c.format = f.format;
  const bool bytes = f.format == PanoramaFormat::BgrU8;
  (bytes ? c.bgr8.resize(3 * std::size_t(w) * std::size_t(h))
         : c.rgb.resize(3 * std::size_t(w) * std::size_t(h)));
  for (int y = 0; y < h; ++y) {
    const std::size_t from = 3 * (std::size_t(y0 + y) * std::size_t(f.width) + std::size_t(x0));
    const std::size_t to = 3 * std::size_t(y) * std::size_t(w), n = 3 * std::size_t(w);
    if (bytes)
      std::copy_n(f.bgr8.data() + from, n, c.bgr8.data() + to);
    else
      std::copy_n(f.rgb.data() + from, n, c.rgb.data() + to);
  }
  return c;
}

/// The window about a circle (liveprobe's pixel coordinates) reaching `margin` pixels past its
/// rim, within the frame.
FrameWindow windowAbout(const Frame& f, double x, double y, double radius, double margin) {
  const double reach = radius + margin;
  const int x0 = std::max(0, int(std::floor(x - reach))),
            y0 = std::max(0, int(std::floor(y - reach)));
  const int x1 = std::min(f.width, int(std::ceil(x + reach))),
            y1 = std::min(f.height, int(std::ceil(y + reach)));
  return {x0, y0, std::max(0, x1 - x0), std::max(0, y1 - y0)};
}

/// A ball's rim read cheaply about `near` (liveprobe's pixel coordinates): the circle through its
/// strongest radial edge within a band of the radius, on at least half the rays; none when the
/// rim is not there. In liveprobe's pixel coordinates.
std::optional<cv::Vec3d> rimReading(const Frame& frame, const BallCircle& near, double band) {
  const FrameWindow window = windowAbout(frame, near.x, near.y, near.radius, band + 8);
  const auto [x0, y0, w, h] = window;
  if (w < 16 || h < 16) return std::nullopt;
  const cv::Mat grey = greyOf(cropOf(frame, window));
  // (OpenCV's pixel centres are whole numbers; liveprobe's are at +0.5.)
  const cv::Vec3d rough(near.x - 0.5 - x0, near.y - 0.5 - y0, near.radius);
  const auto c = edgeCircle(grey, rough, band, 180);
  if (!c || std::hypot((*c)[0] - rough[0], (*c)[1] - rough[1]) > band ||
      std::abs((*c)[2] - rough[2]) > band)
    return std::nullopt;
  return cv::Vec3d((*c)[0] + 0.5 + x0, (*c)[1] + 0.5 + y0, (*c)[2]);
}

/// The rim's model fitted from a rim reading (within the model's reach of the rim), in a window,
/// at the camera's blur as found before.
std::optional<BallCircle> fitNear(const Frame& frame, const cv::Vec3d& reading, double blur) {
  const FrameWindow window =
      windowAbout(frame, reading[0], reading[1], reading[2], kReach + kSearch + 4);
  const int x0 = window.x, y0 = window.y;
  const auto fit =
      fitRim(linearOf(cropOf(frame, window)),
             cv::Vec3d(reading[0] - 0.5 - x0, reading[1] - 0.5 - y0, reading[2]), blur);
  if (!fit || fit->rimResidual >= kMaxRimResidual) return std::nullopt;
  BallCircle c = *fit;
  c.x += x0, c.y += y0;
  return c;
}

}  // namespace

std::optional<BallCircle> findBall(const Frame& frame) {
  if (frame.width < 16 || frame.height < 16) return std::nullopt;
  const cv::Mat grey = greyOf(frame);
  const int side = std::min(frame.width, frame.height);
  cv::Mat smooth;
  grey.convertTo(smooth, CV_8U, 255);
  cv::GaussianBlur(smooth, smooth, cv::Size(5, 5), 1.5);
  std::vector<cv::Vec3f> circles;
  cv::HoughCircles(smooth, circles, cv::HOUGH_GRADIENT_ALT, 1.5, side, 300, 0.8, side / 10,
                   side / 2);
  if (circles.empty())
    cv::HoughCircles(smooth, circles, cv::HOUGH_GRADIENT, 1.5, side, 100, 40, side / 10, side / 2);
  // The Hough circle is rough (tens of pixels at the rim's weak contrast): the rim's edge within
  // 15% of its radius, then within 4 pixels of that, then the rim's model.
  // Of the candidates' rims, the one the model fits best: a ring inside the ball (a railing's
  // reflection) can pass the edge's tests, but its profile is not a rim's.
  const cv::Mat linear = linearOf(frame);
  std::optional<BallCircle> best;
  for (const cv::Vec3f& c : circles)
    if (auto first = edgeCircle(grey, cv::Vec3d(c[0], c[1], c[2]), 0.15 * c[2], 90))
      if (auto second = edgeCircle(grey, *first, 4.0, 180))
        if (auto fit = fitRim(linear, *second))
          if (fit->rimResidual < kMaxRimResidual && (!best || fit->rimResidual < best->rimResidual))
            best = fit;
  return best;
}

std::optional<BallCircle> findBallWithin(const Frame& frame, const FrameWindow& window) {
  const int x0 = std::clamp(window.x, 0, frame.width), y0 = std::clamp(window.y, 0, frame.height);
  const int w = std::min(window.width, frame.width - x0),
            h = std::min(window.height, frame.height - y0);
  if (w < 16 || h < 16) return std::nullopt;
  auto found = findBall(cropOf(frame, {x0, y0, w, h}));
  if (found) found->x += x0, found->y += y0;
  return found;
}

BallFollower::Step BallFollower::follow(const Frame& frame) {
  // The band the rim is read in: a ball that moves a few pixels a frame stays in it.
  const auto band = [](const BallCircle& c) { return std::max(6.0, 0.04 * c.radius); };
  Step step;
  if (!circle_ || (lost_ && ++lostFrames_ % kSearchEvery == 0)) {  // the whole frame
    if (auto c = searchWithin_ ? findBallWithin(frame, *searchWithin_) : findBall(frame))
      if (auto reading = rimReading(frame, *c, band(*c))) {
        step.event = !circle_ ? Event::Found : Event::FoundAgain;
        circle_ = *c, reading_ = {(*reading)[0], (*reading)[1], (*reading)[2]};
        lost_ = false, lostFrames_ = 0;
      }
    if (step.event != Event::None || !circle_) {
      step.circle = circle_;
      return step;
    }
  }
  const std::optional<cv::Vec3d> reading = rimReading(frame, *circle_, band(*circle_));
  std::optional<BallCircle> fit = circle_;
  if (reading && std::max({std::hypot((*reading)[0] - reading_[0], (*reading)[1] - reading_[1]),
                           std::abs((*reading)[2] - reading_[2])}) > kMovedPixels) {
    // The reading is biased (the strongest edge lies just inside the rim): the model, from it.
    fit = fitNear(frame, *reading, circle_->rimBlur);
    if (fit) {
      circle_ = *fit, reading_ = {(*reading)[0], (*reading)[1], (*reading)[2]};
      step.event = Event::Moved;
    }
  }
  step.circle = circle_;
  if (!reading || !fit) {
    step.lost = true;
    if (!lost_) step.event = Event::Lost;
    lost_ = true;
  } else if (lost_) {
    step.event = Event::FoundAgain, lost_ = false, lostFrames_ = 0;
  }
  return step;
}

}  // namespace lp
