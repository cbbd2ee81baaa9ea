#include "shading/sh.h"

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
  return {0.282095f,
          0.488603f * y,
          0.488603f * z,
          0.488603f * x,
          1.092548f * x * y,
          1.092548f * y * z,
          0.315392f * (3.0f * z * z - 1.0f),
          1.092548f * x * z,
          0.546274f * (x * x - y * y)};
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
  // R&H eq. 12: the A_l and the basis constants folded together. c1 = A2 * 0.546274,
  // c3 = 3 * A2 * 0.315392, c4 = A0 * 0.282095, c5 = A2 * 0.315392, and c2 = A1 * 0.488603 / 2
  // (off-diagonal terms appear twice in n4^T M n4, so their entries carry half; likewise c1
  // for the xy, yz and xz terms, whose basis constant 1.092548 is twice 0.546274).
  constexpr float c1 = 0.429043f, c2 = 0.511664f, c3 = 0.743125f, c4 = 0.886227f,
                  c5 = 0.247708f;
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
    return 0.5f * (1.0f + std::cos(3.14159265358979f * float(l) / w));
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
  const float golden = 3.14159265358979f * (3.0f - std::sqrt(5.0f));
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

}  // namespace lp

namespace lp {

// Exact pixel integrals for the equirect layout. With u = cos t, each basis function is
// Y = K g(t) f(p), and the integral over a pixel is K (int g(t) sin t dt)(int f(p) dp):
//   g: 1, cos t, sin t, sin t cos t, sin^2 t, 3 cos^2 t - 1
//   int_{t0}^{t1} g sin t dt = int_{u1}^{u0} g du:
//     1 -> u0 - u1;  cos -> (u0^2 - u1^2)/2;  3u^2-1 -> (u0^3 - u0) - (u1^3 - u1);
//     sin^2 -> (u0 - u0^3/3) - (u1 - u1^3/3);  sin -> [t/2 - sin 2t/4]_{t0}^{t1};
//     sin cos -> [sin^3 t / 3]_{t0}^{t1}
//   f: 1, cos p, sin p, cos 2p, sin 2p with the obvious antiderivatives.
// Basis in these factors: Y00 = k0; Y1-1 = k1 sin t sin p; Y10 = k1 cos t; Y11 = k1 sin t cos p;
// Y2-2 = (k2/2) sin^2 t sin 2p; Y2-1 = k2 sin t cos t sin p; Y20 = k3 (3cos^2 t - 1);
// Y21 = k2 sin t cos t cos p; Y22 = k4 sin^2 t cos 2p.
EquirectProjector::EquirectProjector(int width, int height) : width_(width), height_(height) {
  const double pi = 3.14159265358979323846;
  for (auto& c : col_) c.resize(std::size_t(width));
  for (int j = 0; j < width; ++j) {
    const double p0 = 2 * pi * j / width, p1 = 2 * pi * (j + 1) / width;
    col_[0][j] = float(p1 - p0);
    col_[1][j] = float(std::sin(p1) - std::sin(p0));
    col_[2][j] = float(std::cos(p0) - std::cos(p1));
    col_[3][j] = float((std::sin(2 * p1) - std::sin(2 * p0)) / 2);
    col_[4][j] = float((std::cos(2 * p0) - std::cos(2 * p1)) / 2);
  }
  for (auto& r : row_) r.resize(std::size_t(height));
  for (int i = 0; i < height; ++i) {
    const double t0 = pi * i / height, t1 = pi * (i + 1) / height;
    const double u0 = std::cos(t0), u1 = std::cos(t1);
    row_[0][i] = u0 - u1;
    row_[1][i] = (u0 * u0 - u1 * u1) / 2;
    row_[2][i] = (t1 / 2 - std::sin(2 * t1) / 4) - (t0 / 2 - std::sin(2 * t0) / 4);
    row_[3][i] = (std::pow(std::sin(t1), 3) - std::pow(std::sin(t0), 3)) / 3;
    row_[4][i] = (u0 - u0 * u0 * u0 / 3) - (u1 - u1 * u1 * u1 / 3);
    row_[5][i] = (u0 * u0 * u0 - u0) - (u1 * u1 * u1 - u1);
  }
}

void EquirectProjector::projectRows(const float* rgb, std::size_t rowStride, int row0, int row1,
                                    double* out) const {
  constexpr double k0 = 0.282095, k1 = 0.488603, k2 = 1.092548, k3 = 0.315392, k4 = 0.546274;
  const float *c1 = col_[0].data(), *cc = col_[1].data(), *cs = col_[2].data(),
              *cc2 = col_[3].data(), *cs2 = col_[4].data();
  for (int i = row0; i < row1; ++i) {
    const float* px = rgb + std::size_t(i) * rowStride;
    // Five column-weighted sums per channel: 15 multiply-adds per pixel.
    float s[5][3] = {};
    for (int j = 0; j < width_; ++j) {
      const float r = px[3 * j], g = px[3 * j + 1], b = px[3 * j + 2];
      s[0][0] += c1[j] * r, s[0][1] += c1[j] * g, s[0][2] += c1[j] * b;
      s[1][0] += cc[j] * r, s[1][1] += cc[j] * g, s[1][2] += cc[j] * b;
      s[2][0] += cs[j] * r, s[2][1] += cs[j] * g, s[2][2] += cs[j] * b;
      s[3][0] += cc2[j] * r, s[3][1] += cc2[j] * g, s[3][2] += cc2[j] * b;
      s[4][0] += cs2[j] * r, s[4][1] += cs2[j] * g, s[4][2] += cs2[j] * b;
    }
    const double R1 = row_[0][i], Rc = row_[1][i], Rs = row_[2][i], Rsc = row_[3][i],
                 Rs2 = row_[4][i], R3 = row_[5][i];
    for (int ch = 0; ch < 3; ++ch) {
      const double S1 = s[0][ch], Sc = s[1][ch], Ss = s[2][ch], Sc2 = s[3][ch], Ss2 = s[4][ch];
      out[0 * 3 + ch] += k0 * R1 * S1;
      out[1 * 3 + ch] += k1 * Rs * Ss;
      out[2 * 3 + ch] += k1 * Rc * S1;
      out[3 * 3 + ch] += k1 * Rs * Sc;
      out[4 * 3 + ch] += 0.5 * k2 * Rs2 * Ss2;
      out[5 * 3 + ch] += k2 * Rsc * Ss;
      out[6 * 3 + ch] += k3 * R3 * S1;
      out[7 * 3 + ch] += k2 * Rsc * Sc;
      out[8 * 3 + ch] += k4 * Rs2 * Sc2;
    }
  }
}

Sh9 EquirectProjector::project(const float* rgb, std::size_t rowStride) const {
  std::array<double, 27> acc{};
  projectRows(rgb, rowStride, 0, height_, acc.data());
  Sh9 out;
  for (int k = 0; k < kShCount; ++k)
    out.c[k] = Rgb(float(acc[3 * k]), float(acc[3 * k + 1]), float(acc[3 * k + 2]));
  return out;
}

Sh9 projectEquirect(const float* rgb, int width, int height) {
  return EquirectProjector(width, height).project(rgb, std::size_t(width) * 3);
}

}  // namespace lp

namespace lp {

glm::mat3 rotationYawPitchRoll(float yawDeg, float pitchDeg, float rollDeg) {
  const float y = glm::radians(yawDeg), p = glm::radians(pitchDeg), r = glm::radians(rollDeg);
  const glm::mat3 rz(glm::vec3(std::cos(y), std::sin(y), 0), glm::vec3(-std::sin(y), std::cos(y), 0),
                     glm::vec3(0, 0, 1));
  const glm::mat3 ry(glm::vec3(std::cos(p), 0, -std::sin(p)), glm::vec3(0, 1, 0),
                     glm::vec3(std::sin(p), 0, std::cos(p)));
  const glm::mat3 rx(glm::vec3(1, 0, 0), glm::vec3(0, std::cos(r), std::sin(r)),
                     glm::vec3(0, -std::sin(r), std::cos(r)));
  return rz * ry * rx;
}

Sh9 rotateSh(const Sh9& L, const glm::mat3& R) {
  Sh9 out;
  out.c[0] = L.c[0];
  // Band 1: sum_m L1m Y1m(w) = 0.488603 (L11, L1-1, L10) . w, so the vector turns with R.
  for (int ch = 0; ch < 3; ++ch) {
    const glm::vec3 v = R * glm::vec3(L.c[3][ch], L.c[1][ch], L.c[2][ch]);
    out.c[3][ch] = v.x, out.c[1][ch] = v.y, out.c[2][ch] = v.z;
  }
  // Band 2: the rotated coefficients c' satisfy sum c'_m Y2m(w_i) = sum c_m Y2m(R^T w_i) at every w_i. Least squares
  // over 12 icosahedron directions: (A^T A) c' = A^T B c, A_im = Y2m(w_i), B_im = Y2m(R^T w_i).
  const float g = 1.61803399f;
  const glm::vec3 dirs[12] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                              {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  double A[12][5], B[12][5];
  const glm::mat3 Rt = glm::transpose(R);
  for (int i = 0; i < 12; ++i) {
    const glm::vec3 w = glm::normalize(dirs[i]);
    const auto ya = shBasis(w), yb = shBasis(Rt * w);
    for (int m = 0; m < 5; ++m) A[i][m] = ya[4 + m], B[i][m] = yb[4 + m];
  }
  double ata[5][5] = {}, atb[5][5] = {};
  for (int i = 0; i < 12; ++i)
    for (int a = 0; a < 5; ++a)
      for (int b = 0; b < 5; ++b) ata[a][b] += A[i][a] * A[i][b], atb[a][b] += A[i][a] * B[i][b];
  // Solve ata X = atb (Gauss-Jordan with partial pivoting; ata is well conditioned).
  for (int col = 0; col < 5; ++col) {
    int piv = col;
    for (int r = col + 1; r < 5; ++r)
      if (std::abs(ata[r][col]) > std::abs(ata[piv][col])) piv = r;
    std::swap(ata[col], ata[piv]);
    std::swap(atb[col], atb[piv]);
    for (int r = 0; r < 5; ++r) {
      if (r == col) continue;
      const double f = ata[r][col] / ata[col][col];
      for (int k = 0; k < 5; ++k) ata[r][k] -= f * ata[col][k], atb[r][k] -= f * atb[col][k];
    }
  }
  for (int ch = 0; ch < 3; ++ch)
    for (int m = 0; m < 5; ++m) {
      double v = 0;
      for (int k = 0; k < 5; ++k) v += atb[m][k] / ata[m][m] * L.c[4 + k][ch];
      out.c[4 + m][ch] = float(v);
    }
  return out;
}

}  // namespace lp
