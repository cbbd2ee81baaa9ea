#include "unseen.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace lp::unseen {

double coverage(const std::vector<SphereSample>& samples) {
  double sum = 0;
  for (const SphereSample& s : samples) sum += s.solidAngle;
  const double share = sum / (4.0 * kPi);
  return share >= 1.0 - kWhole ? 1.0 : share;
}

namespace {

/// A piece of the sphere the frame does not see: its direction and solid angle.
struct Piece {
  glm::vec3 dir;
  double solidAngle;
};

/// Whether the frame sees each direction: it lands on a pixel that measures something.
std::vector<char> seen(const LayoutSpec& spec, int width, int height,
                       const std::vector<SphereSample>& samples,
                       const std::vector<glm::vec3>& dirs) {
  std::vector<glm::vec2> at(dirs.size());
  layoutPixels(spec, width, height, dirs.data(), dirs.size(), at.data());
  std::vector<char> out(dirs.size(), 0);
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    if (!(at[i].x >= 0 && at[i].x < float(width) && at[i].y >= 0 && at[i].y < float(height)))
      continue;
    const std::size_t p = std::size_t(at[i].y) * std::size_t(width) + std::size_t(at[i].x);
    out[i] = samples[p].solidAngle > 0.0f;
  }
  return out;
}

glm::vec3 direction(double t, double p) {
  return {float(std::sin(t) * std::cos(p)), float(std::sin(t) * std::sin(p)), float(std::cos(t))};
}

/// The unseen pieces of the sphere: cells of a 256 x 128 latitude-longitude grid whose corners
/// and centre the frame all misses, and the 8 x 8 sub-cells it misses of cells it partly sees.
std::vector<Piece> unseenPieces(const LayoutSpec& spec, int width, int height,
                                const std::vector<SphereSample>& samples) {
  constexpr int kW = 256, kH = 128, kSub = 8;
  std::vector<glm::vec3> dirs;
  dirs.reserve(std::size_t(kW + 1) * (kH + 1) + std::size_t(kW) * kH);
  for (int i = 0; i <= kH; ++i)
    for (int j = 0; j <= kW; ++j) dirs.push_back(direction(kPi * i / kH, 2 * kPi * j / kW));
  for (int i = 0; i < kH; ++i)
    for (int j = 0; j < kW; ++j)
      dirs.push_back(direction(kPi * (i + 0.5) / kH, 2 * kPi * (j + 0.5) / kW));
  const std::vector<char> s = seen(spec, width, height, samples, dirs);
  const auto corner = [&](int i, int j) { return s[std::size_t(i) * (kW + 1) + std::size_t(j)]; };
  const std::size_t centres = std::size_t(kW + 1) * (kH + 1);

  std::vector<Piece> pieces;
  std::vector<glm::vec3> subDirs;
  std::vector<double> subAngles;
  for (int i = 0; i < kH; ++i) {
    for (int j = 0; j < kW; ++j) {
      const char c = s[centres + std::size_t(i) * kW + std::size_t(j)];
      const bool uniform = corner(i, j) == c && corner(i, j + 1) == c && corner(i + 1, j) == c &&
                           corner(i + 1, j + 1) == c;
      if (uniform) {
        if (!c) {
          const double t0 = kPi * i / kH, t1 = kPi * (i + 1) / kH;
          pieces.push_back({dirs[centres + std::size_t(i) * kW + std::size_t(j)],
                            (2 * kPi / kW) * (std::cos(t0) - std::cos(t1))});
        }
        continue;
      }
      for (int a = 0; a < kSub; ++a) {
        const double t0 = kPi * (i * kSub + a) / (kH * kSub),
                     t1 = kPi * (i * kSub + a + 1) / (kH * kSub);
        const double dw = (2 * kPi / (kW * kSub)) * (std::cos(t0) - std::cos(t1));
        for (int b = 0; b < kSub; ++b) {
          subDirs.push_back(direction((t0 + t1) / 2, 2 * kPi * (j * kSub + b + 0.5) / (kW * kSub)));
          subAngles.push_back(dw);
        }
      }
    }
  }
  const std::vector<char> sub = seen(spec, width, height, samples, subDirs);
  for (std::size_t n = 0; n < subDirs.size(); ++n)
    if (!sub[n]) pieces.push_back({subDirs[n], subAngles[n]});
  return pieces;
}

/// The seen pixels next to an unseen one or to the frame's border.
std::vector<std::size_t> edgePixels(int width, int height,
                                    const std::vector<SphereSample>& samples) {
  const auto unseenAt = [&](int x, int y) {
    return x < 0 || y < 0 || x >= width || y >= height ||
           samples[std::size_t(y) * std::size_t(width) + std::size_t(x)].solidAngle <= 0.0f;
  };
  std::vector<std::size_t> edge;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      if (!unseenAt(x, y) &&
          (unseenAt(x - 1, y) || unseenAt(x + 1, y) || unseenAt(x, y - 1) || unseenAt(x, y + 1)))
        edge.push_back(std::size_t(y) * std::size_t(width) + std::size_t(x));
  return edge;
}

void addBasis(std::array<double, 9>& into, const Piece& piece) {
  const auto y = shBasis(piece.dir);
  for (int k = 0; k < kShCount; ++k) into[k] += double(y[k]) * piece.solidAngle;
}

std::array<float, kShCount> toFloat(const std::array<double, 9>& w) {
  std::array<float, kShCount> out{};
  for (int k = 0; k < kShCount; ++k) out[k] = float(w[k]);
  return out;
}

}  // namespace

std::array<float, kShCount> Fill::at(std::size_t p, const SphereSample& s) const {
  std::array<float, kShCount> out{};
  if (hasGround) {
    const float cosine = s.solidAngle * std::max(0.0f, glm::dot(s.dir, up));
    for (int k = 0; k < kShCount; ++k) out[k] = cosine * ground[k];
  }
  const auto it = std::lower_bound(pixels.begin(), pixels.end(), p);
  if (it != pixels.end() && *it == p) {
    const auto& w = weights[std::size_t(it - pixels.begin())];
    for (int k = 0; k < kShCount; ++k) out[k] += w[k];
  }
  return out;
}

Fill fill(const LayoutSpec& spec, int width, int height, const std::vector<SphereSample>& samples) {
  Fill out;
  if (spec.unseen.fill == UnseenRule::Fill::Black || coverage(samples) == 1.0) return out;
  const std::vector<Piece> pieces = unseenPieces(spec, width, height, samples);
  const std::vector<std::size_t> edge = edgePixels(width, height, samples);
  if (pieces.empty() || edge.empty()) return out;
  out.pixels = edge;

  if (spec.unseen.fill == UnseenRule::Fill::Mean) {
    std::array<double, 9> all{};
    for (const Piece& piece : pieces) addBasis(all, piece);
    double edgeAngle = 0;
    for (const std::size_t p : edge) edgeAngle += samples[p].solidAngle;
    for (const std::size_t p : edge) {
      std::array<double, 9> w{};
      for (int k = 0; k < kShCount; ++k) w[k] = all[k] * samples[p].solidAngle / edgeAngle;
      out.weights.push_back(toFloat(w));
    }
    return out;
  }

  // Ground: the unseen sky takes its nearest edge pixel (directions as structure of arrays for
  // the search), the unseen ground the albedo times what reaches an upward normal.
  std::vector<float> ex(edge.size()), ey(edge.size()), ez(edge.size());
  for (std::size_t e = 0; e < edge.size(); ++e) {
    const glm::vec3 d = samples[edge[e]].dir;
    ex[e] = d.x, ey[e] = d.y, ez[e] = d.z;
  }
  std::vector<std::array<double, 9>> fromEdge(edge.size());
  std::vector<double> upFromEdge(edge.size(), 0.0);
  std::array<double, 9> ground{};
  const glm::vec3 up = glm::normalize(spec.unseen.up);
  for (const Piece& piece : pieces) {
    const float height = glm::dot(piece.dir, up);
    if (height < 0) {
      addBasis(ground, piece);
      continue;
    }
    std::size_t best = 0;
    float bestDot = -2.0f;
    for (std::size_t e = 0; e < edge.size(); ++e) {
      const float dot = ex[e] * piece.dir.x + ey[e] * piece.dir.y + ez[e] * piece.dir.z;
      if (dot > bestDot) bestDot = dot, best = e;
    }
    addBasis(fromEdge[best], piece);
    upFromEdge[best] += double(height) * piece.solidAngle;
  }
  // L_ground = albedo E_up / pi, E_up = sum over pixels of L max(dir . up, 0) dw (and the sky's
  // fill, which the edge pixels carry).
  const double k = double(spec.unseen.albedo) / kPi;
  for (int c = 0; c < kShCount; ++c) ground[c] *= k;
  for (std::size_t e = 0; e < edge.size(); ++e) {
    for (int c = 0; c < kShCount; ++c) fromEdge[e][c] += ground[c] * upFromEdge[e];
    out.weights.push_back(toFloat(fromEdge[e]));
  }
  out.hasGround = true;
  out.ground = toFloat(ground);
  out.up = up;
  return out;
}

}  // namespace lp::unseen
