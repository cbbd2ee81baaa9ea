#include "shading/sh.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "project_kernel.h"
#include "shading/thread_pool.h"

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
  constexpr float c1 = 0.429043f, c2 = 0.511664f, c3 = 0.743125f, c4 = 0.886227f, c5 = 0.247708f;
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
  constexpr double k0 = 0.282095, k1 = 0.488603, k2 = 1.092548, k3 = 0.315392, k4 = 0.546274;
  auto t = std::make_shared<kernel::EquirectTables>();
  t->width = width;
  t->height = height;
  const std::size_t padded = (std::size_t(width) + 15) / 16 * 16;
  for (auto& c : t->col) c.assign(padded, 0.0f);
  for (int j = 0; j < width; ++j) {
    const double p0 = 2 * pi * j / width, p1 = 2 * pi * (j + 1) / width;
    t->col[0][j] = float(p1 - p0);
    t->col[1][j] = float(std::sin(p1) - std::sin(p0));
    t->col[2][j] = float(std::cos(p0) - std::cos(p1));
    t->col[3][j] = float((std::sin(2 * p1) - std::sin(2 * p0)) / 2);
    t->col[4][j] = float((std::cos(2 * p0) - std::cos(2 * p1)) / 2);
  }
  // Row factors with the basis constants folded in (slots as kernel::kRowOf uses them).
  for (auto& r : t->row) r.resize(std::size_t(height));
  for (int i = 0; i < height; ++i) {
    const double t0 = pi * i / height, t1 = pi * (i + 1) / height;
    const double u0 = std::cos(t0), u1 = std::cos(t1);
    const double one = u0 - u1;
    const double cosT = (u0 * u0 - u1 * u1) / 2;
    const double sinT = (t1 / 2 - std::sin(2 * t1) / 4) - (t0 / 2 - std::sin(2 * t0) / 4);
    const double sinCos = (std::pow(std::sin(t1), 3) - std::pow(std::sin(t0), 3)) / 3;
    const double sin2 = (u0 - u0 * u0 * u0 / 3) - (u1 - u1 * u1 * u1 / 3);
    const double threeCos2 = (u0 * u0 * u0 - u0) - (u1 * u1 * u1 - u1);
    // Each coefficient k uses one row factor; the kernel multiplies it by one column sum:
    // L00 = k0 R1 S1; L1-1 = k1 Rs Ssin; L10 = k1 Rc S1; L11 = k1 Rs Scos; L2-2 = k2/2 Rs2 Ssin2;
    // L2-1 = k2 Rsc Ssin; L20 = k3 R3 S1; L21 = k2 Rsc Scos; L22 = k4 Rs2 Scos2.
    // Row factor slots (kernel::kRowOf): 0 k0*one, 1 k1*cosT, 2 k1*sinT, 3 k2*sinCos,
    // 4 sin2 (times k2/2 for L2-2 or k4 for L22: equal, since k2/2 = k4), 5 k3*threeCos2.
    t->row[0][i] = float(k0 * one);
    t->row[1][i] = float(k1 * cosT);
    t->row[2][i] = float(k1 * sinT);
    t->row[3][i] = float(k2 * sinCos);
    t->row[4][i] = float(k4 * sin2);
    t->row[5][i] = float(k3 * threeCos2);
  }
  tables_ = std::move(t);
}

template <class RowFill>
Sh9 EquirectProjector::run(RowFill fill, bool bgr, ThreadPool* pool) const {
  // Row bands of at least 32 rows per task; each task sums into its own doubles.
  const unsigned tasks =
      pool ? std::min<unsigned>(pool->size() * 4, unsigned(std::max(1, height_ / 32))) : 1;
  std::vector<std::array<double, 27>> part(tasks);
  auto band = [&](unsigned b) {
    part[b].fill(0.0);
    const int r0 = int(std::int64_t(height_) * b / tasks),
              r1 = int(std::int64_t(height_) * (b + 1) / tasks);
    std::vector<float> buffer;
    kernel::equirectRows(
        *tables_, [&](int i) { return fill(i, buffer); },
        bgr ? kernel::RowOrder::Bgr : kernel::RowOrder::Rgb, r0, r1, part[b].data());
  };
  if (pool)
    pool->run(tasks, band);
  else
    band(0);
  std::array<double, 27> acc{};
  for (const auto& p : part)
    for (int q = 0; q < 27; ++q) acc[q] += p[q];
  Sh9 out;
  for (int k = 0; k < kShCount; ++k)
    out.c[k] = Rgb(float(acc[3 * k]), float(acc[3 * k + 1]), float(acc[3 * k + 2]));
  return out;
}

Sh9 EquirectProjector::project(const float* rgb, std::size_t rowStride, ThreadPool* pool) const {
  return run([&](int i, std::vector<float>&) { return rgb + std::size_t(i) * rowStride; }, false,
             pool);
}

Sh9 EquirectProjector::projectBgr8(const std::uint8_t* bgr, std::size_t rowStride, const float* lut,
                                   ThreadPool* pool) const {
  const std::size_t n = std::size_t(width_) * 3;
  return run(
      [&, n](int i, std::vector<float>& buf) {
        buf.resize(n);
        kernel::lutToFloat(bgr + std::size_t(i) * rowStride, lut, buf.data(), n);
        return static_cast<const float*>(buf.data());
      },
      true, pool);
}

Sh9 EquirectProjector::projectHalf(const std::uint16_t* rgb, std::size_t rowStride,
                                   ThreadPool* pool) const {
  const std::size_t n = std::size_t(width_) * 3;
  return run(
      [&, n](int i, std::vector<float>& buf) {
        buf.resize(n);
        kernel::halfToFloat(rgb + std::size_t(i) * rowStride, buf.data(), n);
        return static_cast<const float*>(buf.data());
      },
      false, pool);
}

SampleProjector::SampleProjector(const SphereSample* samples, std::size_t count)
    : count_(count), w_((count + 15) / 16 * 16 * kShCount, 0.0f) {
  for (std::size_t i = 0; i < count; ++i) {
    if (samples[i].solidAngle == 0.0f) continue;
    const auto y = shBasis(samples[i].dir);
    for (int k = 0; k < kShCount; ++k)
      w_[((i / 16) * kShCount + k) * 16 + i % 16] = y[k] * samples[i].solidAngle;
  }
}

template <class BlockFill>
Sh9 SampleProjector::run(BlockFill fill, bool bgr, ThreadPool* pool) const {
  constexpr std::size_t kChunk = 16384;
  const auto chunks = unsigned((count_ + kChunk - 1) / kChunk);
  std::vector<std::array<double, 27>> part(chunks);
  auto task = [&](unsigned c) {
    part[c].fill(0.0);
    const std::size_t i0 = c * kChunk, n = std::min(kChunk, count_ - i0);  // kChunk % 16 == 0
    std::vector<float> buf;
    kernel::weightedSums(fill(i0, n, buf), n, w_.data() + i0 * kShCount, part[c].data());
  };
  if (pool)
    pool->run(chunks, task);
  else
    for (unsigned c = 0; c < chunks; ++c) task(c);
  std::array<double, 27> acc{};
  for (const auto& p : part)
    for (int q = 0; q < 27; ++q) acc[q] += p[q];
  Sh9 out;
  for (int k = 0; k < kShCount; ++k)
    out.c[k] = bgr ? Rgb(float(acc[3 * k + 2]), float(acc[3 * k + 1]), float(acc[3 * k]))
                   : Rgb(float(acc[3 * k]), float(acc[3 * k + 1]), float(acc[3 * k + 2]));
  return out;
}

Sh9 SampleProjector::project(const float* rgb, ThreadPool* pool) const {
  return run([&](std::size_t i0, std::size_t, std::vector<float>&) { return rgb + 3 * i0; }, false,
             pool);
}

Sh9 SampleProjector::projectBgr8(const std::uint8_t* bgr, const float* lut,
                                 ThreadPool* pool) const {
  return run(
      [&](std::size_t i0, std::size_t n, std::vector<float>& buf) {
        buf.resize(3 * n);
        kernel::lutToFloat(bgr + 3 * i0, lut, buf.data(), 3 * n);
        return static_cast<const float*>(buf.data());
      },
      true, pool);
}

Sh9 projectEquirect(const float* rgb, int width, int height) {
  return EquirectProjector(width, height).project(rgb, std::size_t(width) * 3);
}

}  // namespace lp

namespace lp {

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
  // Band 1: sum_m L1m Y1m(w) = 0.488603 (L11, L1-1, L10) . w, so the vector turns with R.
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
