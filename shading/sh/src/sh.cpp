#include "liveprobe/sh/sh.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lp {

int shIndex(std::string_view name) {
  for (int k = 0; k < kShCount; ++k)
    if (kShNames[k] == name) return k;
  return -1;
}

std::array<float, kShCount> shBasis(glm::vec3 d) {
  const float x = d.x, y = d.y, z = d.z;
  return {kY00,
          kY1 * y,
          kY1 * z,
          kY1 * x,
          kY2 * x * y,
          kY2 * y * z,
          kY20 * (3.0f * z * z - 1.0f),
          kY2 * x * z,
          kY22 * (x * x - y * y)};
}

Sh9 projectSamples(const float* rgb, std::size_t pixelStride, const SphereSample* samples,
                   std::size_t count) {
  // Float partial sums over blocks of 1024 pixels, summed in double: a single float running sum
  // over millions of pixels loses several percent of L00.
  constexpr std::size_t kBlock = 1024;
  std::array<double, 27> total{};
  for (std::size_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::size_t b1 = std::min(count, b0 + kBlock);
    std::array<float, 27> acc{};
    for (std::size_t i = b0; i < b1; ++i) {
      const SphereSample& s = samples[i];
      if (s.solidAngle == 0.0f) continue;
      const float* p = rgb + i * pixelStride;
      const auto y = shBasis(s.dir);
      for (int k = 0; k < kShCount; ++k) {
        const float w = y[k] * s.solidAngle;
        acc[3 * k + 0] += w * p[0];
        acc[3 * k + 1] += w * p[1];
        acc[3 * k + 2] += w * p[2];
      }
    }
    for (int j = 0; j < 27; ++j) total[j] += acc[j];
  }
  Sh9 out;
  for (int k = 0; k < kShCount; ++k)
    out.c[k] = Rgb(float(total[3 * k]), float(total[3 * k + 1]), float(total[3 * k + 2]));
  return out;
}

Sh9 toIrradiance(const Sh9& radiance) {
  Sh9 e = radiance;
  for (int k = 0; k < kShCount; ++k) e.c[k] *= shCosineLobe(shBand(k));
  return e;
}

glm::vec3 evalIrradiance(const Sh9& radiance, glm::vec3 n) {
  const auto y = shBasis(n);
  glm::vec3 e(0.0f);
  for (int k = 0; k < kShCount; ++k) e += shCosineLobe(shBand(k)) * radiance.c[k] * y[k];
  return e;
}

std::array<glm::mat4, 3> irradianceMatrices(const Sh9& L) {
  // R&H eq. 12: the A_l and the basis constants folded together, which gives the paper's
  // c1 = 0.429043, c2 = 0.511664, c3 = 0.743125, c4 = 0.886227, c5 = 0.247708 (tested). The
  // off-diagonal terms appear twice in n4^T M n4, so their entries carry half: c2 = A1 kY1 / 2,
  // and c1 = A2 kY22 serves the xy, yz and xz terms too, since kY2 = 2 kY22.
  constexpr float c1 = kA2 * kY22, c2 = kA1 * kY1 / 2, c3 = 3 * kA2 * kY20, c4 = kA0 * kY00,
                  c5 = kA2 * kY20;
  std::array<glm::mat4, 3> out;
  for (int ch = 0; ch < 3; ++ch) {
    const float L00 = L.c[0][ch], L1m1 = L.c[1][ch], L10 = L.c[2][ch], L11 = L.c[3][ch],
                L2m2 = L.c[4][ch], L2m1 = L.c[5][ch], L20 = L.c[6][ch], L21 = L.c[7][ch],
                L22 = L.c[8][ch];
    // glm::mat4(col0, col1, col2, col3); symmetric, so rows read the same.
    out[ch] = glm::mat4(glm::vec4(c1 * L22, c1 * L2m2, c1 * L21, c2 * L11),
                        glm::vec4(c1 * L2m2, -c1 * L22, c1 * L2m1, c2 * L1m1),
                        glm::vec4(c1 * L21, c1 * L2m1, c3 * L20, c2 * L10),
                        glm::vec4(c2 * L11, c2 * L1m1, c2 * L10, c4 * L00 - c5 * L20));
  }
  return out;
}

glm::vec3 evalIrradianceQuadratic(const std::array<glm::mat4, 3>& m, glm::vec3 n) {
  // Mirrors the GLSL shIrradiance(): vec4 n4 = vec4(n, 1); dot(n4, M * n4) per channel.
  const glm::vec4 n4(n, 1.0f);
  return glm::vec3(glm::dot(n4, m[0] * n4), glm::dot(n4, m[1] * n4), glm::dot(n4, m[2] * n4));
}

BandWindow hannWindow(float w) {
  auto sigma = [w](int l) {
    if (!(w > float(l))) return 0.0f;
    if (std::isinf(w)) return 1.0f;
    return 0.5f * (1.0f + std::cos(float(kPi) * float(l) / w));
  };
  return {sigma(1), sigma(2)};
}

Sh9 applyWindow(const Sh9& radiance, const BandWindow& window) {
  Sh9 out = radiance;
  for (int k = 1; k < 4; ++k) out.c[k] *= window.sigma1;
  for (int k = 4; k < kShCount; ++k) out.c[k] *= window.sigma2;
  return out;
}

namespace {

// f(n) = n4^T M n4 restricted to the unit sphere, and its Euclidean gradient 2 (A n + b).
float quadForm(const glm::mat4& m, glm::vec3 n) {
  const glm::vec4 n4(n, 1.0f);
  return glm::dot(n4, m * n4);
}
glm::vec3 quadGrad(const glm::mat4& m, glm::vec3 n) {
  return 2.0f * glm::vec3(m * glm::vec4(n, 1.0f));
}

}  // namespace

MinIrradiance minIrradiance(const Sh9& radiance) {
  const auto mats = irradianceMatrices(radiance);
  constexpr int kSamples = 4096;
  const float golden = float(kPi) * (3.0f - std::sqrt(5.0f));
  MinIrradiance out;
  for (int ch = 0; ch < 3; ++ch) {
    const glm::mat4& m = mats[ch];
    // Three best seeds from a Fibonacci sphere, each refined by projected gradient descent.
    std::array<std::pair<float, glm::vec3>, 3> seeds;
    seeds.fill({std::numeric_limits<float>::infinity(), glm::vec3(0, 0, 1)});
    for (int i = 0; i < kSamples; ++i) {
      const float z = 1.0f - (2.0f * float(i) + 1.0f) / float(kSamples);
      const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
      const float p = golden * float(i);
      const glm::vec3 n(r * std::cos(p), r * std::sin(p), z);
      const float f = quadForm(m, n);
      if (f < seeds[2].first) {
        seeds[2] = {f, n};
        std::sort(seeds.begin(), seeds.end(),
                  [](const auto& a, const auto& b) { return a.first < b.first; });
      }
    }
    // Step size from the spectral scale of M (Frobenius norm bounds the Lipschitz constant).
    float scale = 0.0f;
    for (int c = 0; c < 4; ++c) scale += glm::dot(m[c], m[c]);
    const float step = scale > 0.0f ? 0.25f / std::sqrt(scale) : 0.0f;
    float best = std::numeric_limits<float>::infinity();
    glm::vec3 bestN(0, 0, 1);
    for (auto [f, n] : seeds) {
      for (int it = 0; it < 200 && step > 0.0f; ++it) {
        const glm::vec3 g = quadGrad(m, n);
        const glm::vec3 gt = g - glm::dot(g, n) * n;  // tangent part
        const glm::vec3 nn = glm::normalize(n - step * gt);
        const float fn = quadForm(m, nn);
        if (!(fn < f)) break;
        n = nn;
        f = fn;
      }
      if (f < best) {
        best = f;
        bestN = n;
      }
    }
    out.value[ch] = best;
    out.normal[ch] = bestN;
  }
  return out;
}

AutoWindow autoWindow(const Sh9& radiance) {
  // Tolerance: irradiance within 1e-6 of the DC term counts as non-negative (float rounding).
  const float tol = 1e-6f * std::max(1e-30f, glm::length(radiance.c[0]));
  auto ok = [&](const BandWindow& w) {
    return minIrradiance(applyWindow(radiance, w)).minOfChannels() >= -tol;
  };
  const float inf = std::numeric_limits<float>::infinity();
  if (ok(BandWindow{})) return {inf, BandWindow{}};
  float lo = 2.0f, hi = 4096.0f;  // ok(lo) holds for non-negative radiance; ok(hi) failed
  if (ok(hannWindow(hi))) return {hi, hannWindow(hi)};
  for (int it = 0; it < 40; ++it) {
    const float mid = std::sqrt(lo * hi);  // bisection in log(w)
    (ok(hannWindow(mid)) ? lo : hi) = mid;
  }
  return {lo, hannWindow(lo)};
}

BandWindow sincWindow(float cutoff) {
  auto sigma = [cutoff](int l) {
    if (!(cutoff > float(l))) return 0.0f;
    const double x = kPi * l / double(cutoff);
    return float(std::pow(std::sin(x) / x, 4.0));
  };
  return {sigma(1), sigma(2)};
}

CmgenWindow cmgenWindow(const Sh9& radiance) {
  constexpr float kBands = 3.0f;
  float cutoff = kBands * 4.0f + 1.0f;
  for (int ch = 0; ch < 3; ++ch) {
    float lo = kBands, hi = cutoff;
    for (int i = 0; i < 16 && lo + 0.1f < hi; ++i) {
      const float mid = 0.5f * (lo + hi);
      const float e = minIrradiance(applyWindow(radiance, sincWindow(mid))).value[ch];
      (e < 0.0f ? hi : lo) = mid;
    }
    cutoff = std::min(cutoff, lo);
  }
  return {cutoff, sincWindow(cutoff)};
}

glm::mat3 rotationYawPitchRoll(float yawDeg, float pitchDeg, float rollDeg) {
  const float y = glm::radians(yawDeg), p = glm::radians(pitchDeg), r = glm::radians(rollDeg);
  const glm::mat3 rz(glm::vec3(std::cos(y), std::sin(y), 0),
                     glm::vec3(-std::sin(y), std::cos(y), 0), glm::vec3(0, 0, 1));
  const glm::mat3 ry(glm::vec3(std::cos(p), 0, -std::sin(p)), glm::vec3(0, 1, 0),
                     glm::vec3(std::sin(p), 0, std::cos(p)));
  const glm::mat3 rx(glm::vec3(1, 0, 0), glm::vec3(0, std::cos(r), std::sin(r)),
                     glm::vec3(0, -std::sin(r), std::cos(r)));
  return rz * ry * rx;
}

const Band2Design& band2Design() {
  static const Band2Design d = [] {
    Band2Design r;
    const float g = 1.6180339887498949f;  // the golden ratio: (0, +-1, +-g) and its cyclic turns
    const glm::vec3 v[12] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                             {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                             {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    for (int i = 0; i < 12; ++i) {
      r.dirs[std::size_t(i)] = glm::normalize(v[i]);
      const auto y = shBasis(r.dirs[std::size_t(i)]);
      for (int m = 0; m < 5; ++m) r.basis[std::size_t(i)][std::size_t(m)] = y[std::size_t(4 + m)];
    }
    // projection = G^-1 A^T with G = A^T A, which is (12 / 4 pi) I up to the basis constants'
    // six digits; inverting the actual G keeps rotation exact to float precision.
    double gm[5][5] = {}, inv[5][5] = {};
    for (int a = 0; a < 5; ++a) {
      inv[a][a] = 1;
      for (int b = 0; b < 5; ++b)
        for (int i = 0; i < 12; ++i)
          gm[a][b] +=
              r.basis[std::size_t(i)][std::size_t(a)] * r.basis[std::size_t(i)][std::size_t(b)];
    }
    for (int col = 0; col < 5; ++col) {  // Gauss-Jordan; G is well conditioned (nearly diagonal)
      for (int row = 0; row < 5; ++row) {
        if (row == col) continue;
        const double f = gm[row][col] / gm[col][col];
        for (int k = 0; k < 5; ++k) gm[row][k] -= f * gm[col][k], inv[row][k] -= f * inv[col][k];
      }
    }
    for (int m = 0; m < 5; ++m)
      for (int i = 0; i < 12; ++i) {
        double v2 = 0;
        for (int k = 0; k < 5; ++k)
          v2 += inv[m][k] / gm[m][m] * r.basis[std::size_t(i)][std::size_t(k)];
        r.projection[std::size_t(m)][std::size_t(i)] = v2;
      }
    return r;
  }();
  return d;
}

Sh9 rotateSh(const Sh9& L, const glm::mat3& R) {
  Sh9 out;
  out.c[0] = L.c[0];
  // Band 1: sum_m L1m Y1m(w) = kY1 (L11, L1-1, L10) . w, so the vector turns with R.
  for (int ch = 0; ch < 3; ++ch) {
    const glm::vec3 v = R * glm::vec3(L.c[3][ch], L.c[1][ch], L.c[2][ch]);
    out.c[3][ch] = v.x, out.c[1][ch] = v.y, out.c[2][ch] = v.z;
  }
  // Band 2: the rotated coefficients satisfy sum c'_m Y2m(w) = sum c_k Y2k(R^T w) for every w.
  // Sampled at the 12 icosahedron vertices (a spherical 5-design), the projection back onto
  // band 2 is a constant 5x12 matrix (Band2Design::projection); per call only the basis at the
  // 12 turned directions is evaluated: no system is solved.
  const auto& d = band2Design();
  const glm::mat3 Rt = glm::transpose(R);
  double rot[5][5] = {};  // rot[m][k] = sum_i projection[m][i] Y2k(R^T w_i)
  for (int i = 0; i < 12; ++i) {
    const auto yb = shBasis(Rt * d.dirs[std::size_t(i)]);
    for (int m = 0; m < 5; ++m)
      for (int k = 0; k < 5; ++k)
        rot[m][k] += d.projection[std::size_t(m)][std::size_t(i)] * yb[std::size_t(4 + k)];
  }
  for (int ch = 0; ch < 3; ++ch)
    for (int m = 0; m < 5; ++m) {
      double v = 0;
      for (int k = 0; k < 5; ++k) v += rot[m][k] * L.c[std::size_t(4 + k)][ch];
      out.c[std::size_t(4 + m)][ch] = float(v);
    }
  return out;
}

}  // namespace lp
