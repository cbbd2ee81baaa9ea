#include "bracket_align.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace lp::align {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// The log-luminance noise of a well-exposed 8-bit reading after block averaging (half a code step
// at code 16 is 3%; chroma subsampling and compression add as much): residuals within it are
// inliers, and the information of an estimate is its Hessian over its square.
constexpr double kNoise = 0.05;
// Huber's threshold and the residual beyond which a pixel is taken for something that moved
// within the scene (or a different reading of a clipped edge) and counts for nothing.
constexpr double kHuber = 0.1, kOutlier = 1.0;
// The prior on the rate: still, give or take 0.5 degrees a frame. A turn the frames show weighs
// far more; a turn they cannot show (a sky alike in every azimuth) is taken as none.
constexpr double kPriorInformation = 1.0 / ((0.5 * kPi / 180) * (0.5 * kPi / 180));
// Frames the tracker keeps: enough to find the last of each exposure of the largest bracket.
constexpr std::size_t kHistory = 10;
// Frames over which rate measurements are combined: two of the largest brackets.
constexpr std::uint64_t kRateSpan = 10;

// The smallest block size dividing both sides that brings the width to 160 or less.
int blockSize(int w, int h) {
  for (int f = 1; f <= w; ++f)
    if (w % f == 0 && h % f == 0 && w / f <= 160) return f;
  return 1;
}

LogLevel halve(const LogLevel& in) {
  LogLevel out;
  if (in.width % 2 || in.height % 2 || in.width < 16) return out;
  out.width = in.width / 2, out.height = in.height / 2;
  out.value.assign(std::size_t(out.width) * out.height, kNaN);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      double sum = 0;
      int n = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const float v = in.value[std::size_t(2 * y + dy) * in.width + std::size_t(2 * x + dx)];
          if (!std::isnan(v)) sum += v, ++n;
        }
      if (n >= 2) out.value[std::size_t(y) * out.width + std::size_t(x)] = float(sum / n);
    }
  return out;
}

// Where unit direction p lies in an equirect image w x h (liveprobe/sh/sh.h's convention), in
// pixel coordinates: column fx (from 0 to w), row fy, pixel centres at whole numbers.
void pixelOf(const glm::dvec3& p, int w, int h, double& fx, double& fy) {
  double phi = std::atan2(p.y, p.x);
  if (phi < 0) phi += 2 * kPi;
  fx = phi / (2 * kPi) * w - 0.5;
  fy = std::acos(std::clamp(p.z, -1.0, 1.0)) / kPi * h - 0.5;
}

// Bilinear sample of an equirect level at direction p (unit); NaN where a corner is unmeasured.
float sample(const LogLevel& l, const glm::dvec3& p) {
  double fx, fy;
  pixelOf(p, l.width, l.height, fx, fy);
  if (fy < 0 || fy > l.height - 1) return kNaN;
  const int x0 = int(std::floor(fx)), y0 = std::min(int(fy), l.height - 2);
  const double ax = fx - x0, ay = fy - y0;
  const int xa = (x0 % l.width + l.width) % l.width, xb = (xa + 1) % l.width;
  const float* r0 = l.value.data() + std::size_t(y0) * l.width;
  const float* r1 = r0 + l.width;
  return float((1 - ay) * ((1 - ax) * r0[xa] + ax * r0[xb]) +
               ay * ((1 - ax) * r1[xa] + ax * r1[xb]));  // NaN spreads
}

struct Normal {
  glm::dmat3 h{0.0};
  glm::dvec3 b{0.0};
  std::size_t overlap = 0, inliers = 0;
};

// Regions of the sphere (8 azimuth sectors by 4 polar bands) whose sums are kept apart: a camera
// turn moves every region alike, an object moving within the scene (the sun across the sky) only
// its own.
constexpr int kSectors = 8, kBands = 4, kRegions = kSectors * kBands;
// The regions of most information left out of an estimate: what a turn rests on must be seen
// elsewhere too (a sun and its glow straddle up to two regions).
constexpr int kLeftOut = 2;

// The normal equations of one Gauss-Newton step at one level: now(d) - old(q d) = J . delta,
// without the kLeftOut regions that hold the most information.
Normal normalEquations(const LogLevel& old, const LogLevel& now, const glm::mat3& q) {
  std::array<Normal, kRegions> part{};
  const int w = now.width, h = now.height;
  const double dphi = 2 * kPi / w, dtheta = kPi / h;
  const glm::dmat3 qd(q);
  for (int y = 1; y < h - 1; ++y) {
    const double theta = kPi * (y + 0.5) / h, st = std::sin(theta), ct = std::cos(theta);
    const float* row = now.value.data() + std::size_t(y) * w;
    Normal* band = part.data() + std::size_t(y * kBands / h) * kSectors;
    for (int x = 0; x < w; ++x) {
      const float v = row[x];
      const float gphi = (row[(x + 1) % w] - row[(x + w - 1) % w]) / float(2 * dphi);
      const float gtheta = (row[x + w] - row[x - w]) / float(2 * dtheta);
      if (std::isnan(v) || std::isnan(gphi) || std::isnan(gtheta)) continue;
      const double phi = 2 * kPi * (x + 0.5) / w, sp = std::sin(phi), cp = std::cos(phi);
      const glm::dvec3 d(st * cp, st * sp, ct), eTheta(ct * cp, ct * sp, -st), ePhi(-sp, cp, 0);
      const float o = sample(old, qd * d);
      if (std::isnan(o)) continue;
      Normal& n = band[x * kSectors / w];
      const double r = double(v) - double(o), a = std::abs(r);
      ++n.overlap;
      if (a > kOutlier) continue;
      n.inliers += a <= 2 * kNoise;
      const glm::dvec3 j = double(gtheta) * ePhi - double(gphi) / st * eTheta;
      const double wt = st * (a <= kHuber ? 1.0 : kHuber / a);
      n.h += wt * glm::outerProduct(j, j);
      n.b += wt * r * j;
    }
  }
  std::array<int, kRegions> order{};
  for (int i = 0; i < kRegions; ++i) order[std::size_t(i)] = i;
  const auto trace = [&](int i) {
    const glm::dmat3& m = part[std::size_t(i)].h;
    return m[0][0] + m[1][1] + m[2][2];
  };
  std::partial_sort(order.begin(), order.begin() + kLeftOut, order.end(),
                    [&](int a, int b) { return trace(a) > trace(b); });
  Normal n;
  for (int k = 0; k < kRegions; ++k) {
    const Normal& p = part[std::size_t(order[std::size_t(k)])];
    n.overlap += p.overlap, n.inliers += p.inliers;
    if (k < kLeftOut) continue;
    n.h += p.h, n.b += p.b;
  }
  return n;
}

// The rotation vector of a rotation (its axis times its angle), for angles below a half turn.
glm::vec3 rotationVector(const glm::mat3& m) {
  const float c = std::clamp((m[0][0] + m[1][1] + m[2][2] - 1.0f) / 2.0f, -1.0f, 1.0f);
  const float angle = std::acos(c);
  const glm::vec3 axis(m[1][2] - m[2][1], m[2][0] - m[0][2], m[0][1] - m[1][0]);
  const float s = glm::length(axis);
  return s > 1e-9f ? axis * (angle / s) : 0.5f * axis;
}

}  // namespace

glm::mat3 rotationFromVector(const glm::vec3& w) {
  const float angle = glm::length(w);
  if (angle < 1e-12f) return glm::mat3(1.0f);
  const glm::vec3 k = w / angle;
  const float c = std::cos(angle), s = std::sin(angle);
  const glm::mat3 skew(glm::vec3(0, k.z, -k.y), glm::vec3(-k.z, 0, k.x), glm::vec3(k.y, -k.x, 0));
  return c * glm::mat3(1.0f) + s * skew + (1 - c) * glm::outerProduct(k, k);
}

LogPyramid logPyramid(const Frame& frame, const ResponseTable& lut, int floor, int clip) {
  LogPyramid p;
  const int f = blockSize(frame.width, frame.height);
  LogLevel& l = p[0];
  l.width = frame.width / f, l.height = frame.height / f;
  l.value.assign(std::size_t(l.width) * l.height, kNaN);
  const int step = std::max(1, f / 4);  // a large block is read on a sparse grid
  const double scale = frame.radianceScale;
  for (int by = 0; by < l.height; ++by)
    for (int bx = 0; bx < l.width; ++bx) {
      double sum = 0;
      int n = 0;
      bool measured = true;
      for (int y = by * f + step / 2; y < (by + 1) * f && measured; y += step) {
        const std::uint8_t* px =
            frame.bgr8.data() + (std::size_t(y) * frame.width + std::size_t(bx) * f) * 3;
        for (int x = step / 2; x < f; x += step) {
          const std::uint8_t* q = px + std::size_t(x) * 3;
          const int hi = std::max({q[0], q[1], q[2]});
          if (hi >= clip || hi <= floor) {
            measured = false;
            break;
          }
          sum += 0.2126 * lut[0][q[2]] + 0.7152 * lut[1][q[1]] + 0.0722 * lut[2][q[0]];
          ++n;
        }
      }
      if (measured && n > 0 && sum > 0)
        l.value[std::size_t(by) * l.width + std::size_t(bx)] = float(std::log(sum / n * scale));
    }
  for (int i = 1; i < kLevels; ++i) p[std::size_t(i)] = halve(p[std::size_t(i - 1)]);
  return p;
}

PairEstimate estimatePair(const LogPyramid& old, const LogPyramid& now, const glm::mat3& guess) {
  PairEstimate e;
  glm::dvec3 total(0.0);
  Normal last;
  for (int level = kLevels - 1; level >= 0; --level) {
    const LogLevel &o = old[std::size_t(level)], &n = now[std::size_t(level)];
    if (n.width == 0 || o.width != n.width || o.height != n.height) continue;
    for (int it = 0; it < (level == 0 ? 3 : 5); ++it) {
      last = normalEquations(o, n, guess * rotationFromVector(glm::vec3(total)));
      // A small ridge keeps a direction the overlap does not constrain (a single bright blob
      // turning about itself) where it was.
      const double ridge = 1e-6 * (last.h[0][0] + last.h[1][1] + last.h[2][2]) + 1e-12;
      const glm::dmat3 a = last.h + ridge * glm::dmat3(1.0);
      if (last.overlap < 30 || std::abs(glm::determinant(a)) < 1e-30) break;
      const glm::dvec3 step = glm::inverse(a) * last.b;
      total += step;
      if (glm::length(step) < 1e-5) break;
    }
  }
  e.delta = glm::vec3(total);
  e.inliers = last.overlap ? double(last.inliers) / double(last.overlap) : 0.0;
  // Trusted where most of a fair overlap agrees once turned, and the turn is a step's (a jump
  // of a tenth of a turn is a cut or a loop, not a camera turning between two frames).
  if (last.overlap >= 30 && e.inliers >= 0.5 && glm::length(total) < 0.3)
    e.information = glm::mat3(last.h / (kNoise * kNoise));
  return e;
}

void RotationTracker::add(LogPyramid pyramid, double scale, std::uint64_t sequence) {
  if (!history_.empty() && (history_.back().pyramid[0].width != pyramid[0].width ||
                            history_.back().pyramid[0].height != pyramid[0].height ||
                            sequence <= history_.back().sequence))
    clear();
  // Rate measurements: the latest earlier frame of the same exposure (the most pixels measured
  // in both), and the frame before where it is of another exposure.
  std::vector<const Entry*> partners;
  for (auto it = history_.rbegin(); it != history_.rend(); ++it)
    if (std::abs(it->scale - scale) <= 0.02 * scale) {
      partners.push_back(&*it);
      break;
    }
  if (!history_.empty() && (partners.empty() || partners.front() != &history_.back()))
    partners.push_back(&history_.back());
  for (const Entry* p : partners) {
    const float gap = float(sequence - p->sequence);
    const PairEstimate e =
        estimatePair(p->pyramid, pyramid, rotationFromVector(ratePerFrame_ * gap));
    if (e.information[0][0] + e.information[1][1] + e.information[2][2] <= 0) continue;
    // The turn measured over `gap` frames, as a rate: its information grows with the gap squared.
    const glm::vec3 turn =
        rotationVector(rotationFromVector(ratePerFrame_ * gap) * rotationFromVector(e.delta));
    measurements_.push_back({sequence, turn / gap, glm::dmat3(e.information) * double(gap * gap)});
  }
  // The rate over the last brackets' measurements, their information combined (a frame that
  // measured nothing, the shortest exposure of a dark scene, is carried by the others).
  while (!measurements_.empty() && measurements_.front().sequence + kRateSpan <= sequence)
    measurements_.pop_front();
  glm::dmat3 info = kPriorInformation * glm::dmat3(1.0);
  glm::dvec3 b(0.0);
  for (const Measurement& m : measurements_) info += m.information, b += m.information * m.rate;
  ratePerFrame_ = glm::vec3(glm::inverse(info) * b);
  history_.push_back({std::move(pyramid), scale, sequence});
  if (history_.size() > kHistory) history_.pop_front();
}

glm::mat3 RotationTracker::turnSince(std::uint64_t sequence) const {
  if (history_.empty() || sequence >= history_.back().sequence) return glm::mat3(1.0f);
  return rotationFromVector(ratePerFrame_ * float(history_.back().sequence - sequence));
}

double displacementPixels(const glm::mat3& q, int width) {
  const double c = std::clamp((double(q[0][0] + q[1][1] + q[2][2]) - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) / (2 * kPi) * width;
}

namespace {

// Where each pixel of one row reads from: the index of the corner above-left (row y0, column
// x0) and of the one above-right (x0 + 1, wrapped), and the bilinear fractions; the corners
// below are a row further.
// Where pixel (x, y) of an equirect frame w x h reads from under the turn qd.
void turnSource(const glm::dmat3& qd, int w, int h, double x, double y, double& fx, double& fy) {
  const double theta = kPi * (y + 0.5) / h, phi = 2 * kPi * (x + 0.5) / w;
  const glm::dvec3 p = qd * glm::dvec3(std::sin(theta) * std::cos(phi),
                                       std::sin(theta) * std::sin(phi), std::cos(theta));
  pixelOf(p, w, h, fx, fy);
}

// A row within 1.1 degrees of a pole: its pixels' sources are found one by one.
bool polarRow(int y, int h) { return std::sin(kPi * (y + 0.5) / h) < 0.02; }

struct RowSamples {
  std::vector<std::uint32_t> left, right;
  std::vector<float> ax, ay;
  explicit RowSamples(int w)
      : left(std::size_t(w)), right(std::size_t(w)), ax(std::size_t(w)), ay(std::size_t(w)) {}
  /// Pixels x0 .. x0 + n - 1 from where they read (fx: column, any value over -w; fy: row), in
  /// one loop without branches (the compiler vectorizes it).
  void set(int x0, int n, const float* __restrict fx, const float* __restrict fy, int w, int h) {
    std::uint32_t* __restrict l = left.data() + x0;
    std::uint32_t* __restrict r = right.data() + x0;
    float* __restrict axOut = ax.data() + x0;
    float* __restrict ayOut = ay.data() + x0;
    const float top = float(h - 1), wf = float(w);
    for (int k = 0; k < n; ++k) {
      const float y = std::clamp(fy[k], 0.0f, top);
      int c0 = int(fx[k] + wf) - w;  // floor, for fx > -w
      axOut[k] = fx[k] - float(c0);
      c0 += c0 < 0 ? w : 0;
      c0 -= c0 >= w ? w : 0;
      const int c1 = c0 + 1 == w ? 0 : c0 + 1;
      const int r0 = std::min(int(y), h - 2);
      ayOut[k] = y - float(r0);
      l[k] = std::uint32_t(r0 * w + c0);
      r[k] = std::uint32_t(r0 * w + c1);
    }
  }
};

}  // namespace

TurnGrid turnGrid(int w, int h, const glm::mat3& q) {
  const glm::dmat3 qd(q);
  TurnGrid g;
  g.nodesX = (w + kTurnGrid - 1) / kTurnGrid + 1, g.nodesY = (h + kTurnGrid - 1) / kTurnGrid + 1;
  g.offset.resize(std::size_t(g.nodesX) * std::size_t(g.nodesY)), g.row.resize(g.offset.size());
  for (int j = 0; j < g.nodesY; ++j)
    for (int i = 0; i < g.nodesX; ++i) {
      double fx, fy;
      turnSource(qd, w, h, i * kTurnGrid, std::min(j * kTurnGrid, h - 1), fx, fy);
      const std::size_t at = std::size_t(j) * std::size_t(g.nodesX) + std::size_t(i);
      g.offset[at] = float(std::remainder(fx - i * kTurnGrid, w));
      g.row[at] = float(fy);
    }
  while (g.polar < h / 2 && polarRow(g.polar, h)) ++g.polar;
  return g;
}

namespace {

// Calls row(y, samples) for every row of an equirect frame w x h (every step-th from step / 2)
// with where its pixels read from under the turn q: exact on a grid every 16 pixels, bilinear
// between (a small turn moves pixels smoothly), exact per pixel within 1.1 degrees of the poles
// (where a turn moves a pixel's azimuth fast).
template <class Row>
void forEachTurnedRow(int w, int h, const glm::mat3& q, Executor* executor, Row row, int step = 1,
                      const TurnGrid* given = nullptr) {
  constexpr int kGrid = kTurnGrid;
  const glm::dmat3 qd(q);
  const auto source = [&](double x, double y, double& fx, double& fy) {
    turnSource(qd, w, h, x, y, fx, fy);
  };
  const TurnGrid made = given ? TurnGrid{} : turnGrid(w, h, q);
  const TurnGrid& grid = given ? *given : made;
  const int gw = grid.nodesX, gh = grid.nodesY;
  const auto nodeY = [&](int j) { return std::min(j * kGrid, h - 1); };
  const std::vector<float>&offset = grid.offset, &rowAt = grid.row;
  parallelFor(executor, std::size_t(h), Split{.grain = 1, .perThread = 4},
              [&](std::size_t y0, std::size_t y1) {
                RowSamples samples(w);
                std::vector<float> o(static_cast<std::size_t>(gw)), r(o);
                std::vector<float> fx(static_cast<std::size_t>(w)), fy(fx);
                for (int y = int(y0); y < int(y1); ++y) {
                  if (y % step != step / 2) continue;
                  if (polarRow(y, h)) {
                    for (int x = 0; x < w; ++x) {
                      double sx, sy;
                      source(x, y, sx, sy);
                      fx[std::size_t(x)] = float(sx), fy[std::size_t(x)] = float(sy);
                    }
                    samples.set(0, w, fx.data(), fy.data(), w, h);
                    row(y, samples);
                    continue;
                  }
                  // This row's nodes, between the grid's rows.
                  const int j = std::min(y / kGrid, gh - 2);
                  const float t = float(y - nodeY(j)) / float(std::max(1, nodeY(j + 1) - nodeY(j)));
                  const float* o0 = offset.data() + std::size_t(j) * gw;
                  const float* r0 = rowAt.data() + std::size_t(j) * gw;
                  for (std::size_t i = 0; i < std::size_t(gw); ++i) {
                    o[i] = o0[i] + t * (o0[i + std::size_t(gw)] - o0[i]);
                    r[i] = r0[i] + t * (r0[i + std::size_t(gw)] - r0[i]);
                  }
                  for (int i = 0; i * kGrid < w; ++i) {
                    const float oa = o[std::size_t(i)], ob = o[std::size_t(i) + 1];
                    const float ra = r[std::size_t(i)], rb = r[std::size_t(i) + 1];
                    const int x0 = i * kGrid, n = std::min(kGrid, w - x0);
                    float* __restrict sx = fx.data() + x0;
                    float* __restrict sy = fy.data() + x0;
                    for (int k = 0; k < n; ++k) {
                      const float s = float(k) * (1.0f / kGrid);
                      sx[k] = float(x0 + k) + oa + s * (ob - oa), sy[k] = ra + s * (rb - ra);
                    }
                  }
                  samples.set(0, w, fx.data(), fy.data(), w, h);
                  row(y, samples);
                }
              });
}

}  // namespace

Coder::Coder(const ResponseTable& response) : linear_(response) {
  for (std::size_t c = 0; c < 3; ++c) {
    const auto& curve = linear_[c];
    const float top = std::max(curve[255], 1e-30f);
    inverseTop_[c] = 1.0f / top;
    for (std::uint32_t i = 0; i <= kLast - kFirst; ++i) {
      // The bucket's middle value; the top bucket is 1 itself.
      const std::uint32_t bits = ((i + kFirst) << 15) | (i + kFirst < kLast ? 1u << 14 : 0u);
      const float v = top * std::bit_cast<float>(bits);
      const auto it = std::lower_bound(curve.begin(), curve.end(), v);
      std::size_t code = std::size_t(it - curve.begin());
      if (code == 256 || (code > 0 && v - curve[code - 1] < curve[code] - v)) --code;
      table_[c][i] = std::uint8_t(i == 0 ? 0 : code);
    }
  }
}

void turnCodes(const std::uint8_t* src, int w, int h, const glm::mat3& q, const Coder& coder,
               int clip, std::uint8_t* dst, Executor* executor, int step, const TurnGrid* grid) {
  // Bilinear in linear units, coded back: a turn of a fraction of a pixel moves a one-pixel sun
  // by that fraction, its power kept. A clipped reading is a bound, not a value: a pixel whose
  // corners are clipped by half their weight or more reads clipped (as the nearest pixel would),
  // otherwise from its unclipped corners alone.
  const ResponseTable& lut = coder.linear();
  const std::size_t stride = std::size_t(w);
  forEachTurnedRow(
      w, h, q, executor,
      [&](int y, const RowSamples& rs) {
        for (int x = step / 2; x < w; x += step) {
          std::uint8_t* out = dst + (std::size_t(y) * stride + std::size_t(x)) * 3;
          const std::size_t at[4] = {rs.left[std::size_t(x)], rs.right[std::size_t(x)],
                                     rs.left[std::size_t(x)] + stride,
                                     rs.right[std::size_t(x)] + stride};
          const float ax = rs.ax[std::size_t(x)], ay = rs.ay[std::size_t(x)];
          const float weight[4] = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
          float r = 0, g = 0, b = 0, unclipped = 0, most = -1;
          for (int k = 0; k < 4; ++k) {
            const std::uint8_t* p = src + at[k] * 3;
            if (std::max({p[0], p[1], p[2]}) >= clip) {
              if (weight[k] > most) most = weight[k], std::copy(p, p + 3, out);
              continue;
            }
            const float wk = weight[k];
            unclipped += wk;
            b += wk * lut[2][p[0]], g += wk * lut[1][p[1]], r += wk * lut[0][p[2]];
          }
          if (unclipped <= 0.5f) continue;  // the clipped corner of most weight, copied
          const float inv = 1.0f / unclipped;
          out[0] = coder.code(2, b * inv), out[1] = coder.code(1, g * inv);
          out[2] = coder.code(0, r * inv);
        }
      },
      step, grid);
}

void turnLuminance(const float* src, int w, int h, const glm::mat3& q, float* dst,
                   Executor* executor) {
  const std::size_t stride = std::size_t(w);
  forEachTurnedRow(w, h, q, executor, [&](int y, const RowSamples& rs) {
    float* out = dst + std::size_t(y) * stride;
    for (std::size_t x = 0; x < stride; ++x) {
      const std::size_t at =
          (rs.ax[x] > 0.5f ? rs.right[x] : rs.left[x]) + (rs.ay[x] > 0.5f ? stride : 0);
      out[x] = src[at];
    }
  });
}

void neighbourhood(const std::uint8_t* bgr, int w, int h, std::uint8_t* low, std::uint8_t* high,
                   Executor* executor) {
  const std::size_t width = std::size_t(w);
  parallelFor(executor, std::size_t(h), Split{.grain = 1, .perThread = 4},
              [&](std::size_t y0, std::size_t y1) {
                // Each row's largest channel once, in a ring of the last three rows.
                std::vector<std::uint8_t> ring(3 * width), least(width), most(width);
                const auto peaks = [&](int y) {
                  const std::uint8_t* __restrict p = bgr + std::size_t(y) * width * 3;
                  std::uint8_t* __restrict out = ring.data() + std::size_t(y % 3) * width;
                  for (std::size_t x = 0; x < width; ++x)
                    out[x] = std::max({p[3 * x], p[3 * x + 1], p[3 * x + 2]});
                };
                int done = -1;  // the last row whose peaks are in the ring
                for (int y = int(y0); y < int(y1); ++y) {
                  // Over this row and the ones above and below, per column.
                  const int above = std::max(0, y - 1), below = std::min(h - 1, y + 1);
                  for (int r = std::max(above, done + 1); r <= below; ++r) peaks(r);
                  done = below;
                  const std::uint8_t* __restrict a = ring.data() + std::size_t(above % 3) * width;
                  const std::uint8_t* __restrict m = ring.data() + std::size_t(y % 3) * width;
                  const std::uint8_t* __restrict b = ring.data() + std::size_t(below % 3) * width;
                  for (std::size_t x = 0; x < width; ++x) {
                    least[x] = std::min({a[x], m[x], b[x]});
                    most[x] = std::max({a[x], m[x], b[x]});
                  }
                  // And the columns beside (the seam wraps).
                  std::uint8_t* __restrict lo = low + std::size_t(y) * width;
                  std::uint8_t* __restrict hi = high + std::size_t(y) * width;
                  const auto ends = [&](std::size_t x, std::size_t left, std::size_t right) {
                    lo[x] = std::min({least[left], least[x], least[right]});
                    hi[x] = std::max({most[left], most[x], most[right]});
                  };
                  ends(0, width - 1, width > 1 ? 1 : 0);
                  for (std::size_t x = 1; x + 1 < width; ++x) {
                    lo[x] = std::min({least[x - 1], least[x], least[x + 1]});
                    hi[x] = std::max({most[x - 1], most[x], most[x + 1]});
                  }
                  if (width > 1) ends(width - 1, width - 2, 0);
                }
              });
}

}  // namespace lp::align
