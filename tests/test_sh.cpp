// Tier 1: the SH core against closed forms and an independent float64 reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <random>

#include "disc_equirect.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/image.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/projector.h"
#include "liveprobe/sh/sh.h"
#include "liveprobe/sh/simd.h"

namespace {

using lp::Sh9;
constexpr double kPi = std::numbers::pi;

// Independent float64 basis in spherical coordinates, with the exact normalisations
// sqrt((2l+1)/(4pi) (l-m)!/(l+m)!) rather than the paper's rounded constants.
std::array<double, 9> refBasis(double t, double p) {
  const double ct = std::cos(t), st = std::sin(t);
  return {0.5 / std::sqrt(kPi),
          std::sqrt(3 / (4 * kPi)) * st * std::sin(p),
          std::sqrt(3 / (4 * kPi)) * ct,
          std::sqrt(3 / (4 * kPi)) * st * std::cos(p),
          std::sqrt(15 / (16 * kPi)) * st * st * std::sin(2 * p),
          std::sqrt(15 / (4 * kPi)) * st * ct * std::sin(p),
          std::sqrt(5 / (16 * kPi)) * (3 * ct * ct - 1),
          std::sqrt(15 / (4 * kPi)) * st * ct * std::cos(p),
          std::sqrt(15 / (16 * kPi)) * st * st * std::cos(2 * p)};
}

glm::vec3 randomUnit(std::mt19937& rng) {
  std::normal_distribution<float> g;
  return glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
}

lp::Image constantEquirect(int w, int h, float c) {
  lp::Image img(w, h);
  std::fill(img.rgb.begin(), img.rgb.end(), c);
  return img;
}

lp::Image randomImage(int w, int h, float maxValue, unsigned seed) {
  lp::Image img(w, h);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, maxValue);
  for (float& v : img.rgb) v = u(rng);
  return img;
}

Sh9 projectImage(const lp::Image& img, lp::Layout layout) {
  return lp::project(lp::PanoramaView::rgbF32(img.rgb.data(), img.width, img.height, layout));
}

TEST(ShCore, BasisMatchesExactNormalisation) {
  std::mt19937 rng(1);
  for (int n = 0; n < 100; ++n) {
    const glm::vec3 d = randomUnit(rng);
    const double t = std::acos(double(d.z)), p = std::atan2(double(d.y), double(d.x));
    const auto ref = refBasis(t, p);
    const auto y = lp::shBasis(d);
    for (int k = 0; k < 9; ++k) EXPECT_NEAR(y[k], ref[k], 2e-6) << "k=" << k;
  }
}

TEST(ShCore, IndexAndNames) {
  EXPECT_EQ(lp::shIndex("L00"), 0);
  EXPECT_EQ(lp::shIndex("L1-1"), 1);
  EXPECT_EQ(lp::shIndex("L2-1"), 5);
  EXPECT_EQ(lp::shIndex("L22"), 8);
  EXPECT_EQ(lp::shIndex("L23"), -1);
  EXPECT_EQ(lp::shBand(3), 1);
  EXPECT_EQ(lp::shBand(4), 2);
}

// Radiance c everywhere: L00 = 4 pi Y00 c, the rest ~0, E = pi c at every normal.
TEST(ShCore, WhiteFurnace) {
  const float c = 1.7f;
  for (auto [w, h] : {std::pair{256, 128}, std::pair{300, 300}, std::pair{97, 31}}) {
    const Sh9 L = projectImage(constantEquirect(w, h, c), lp::Layout::Equirect);
    const double l00 = 4 * kPi * 0.282095 * c;
    for (int ch = 0; ch < 3; ++ch) {
      EXPECT_NEAR(L.c[0][ch], l00, 1e-5 * l00) << w << "x" << h;
      for (int k = 1; k < 9; ++k) EXPECT_NEAR(L.c[k][ch], 0.0, 1e-5 * l00) << "k=" << k;
    }
    const auto m = lp::irradianceMatrices(L);
    std::mt19937 rng(2);
    for (int n = 0; n < 200; ++n) {
      const glm::vec3 nrm = randomUnit(rng);
      const glm::vec3 e1 = lp::evalIrradiance(L, nrm), e2 = lp::evalIrradianceQuadratic(m, nrm);
      for (int ch = 0; ch < 3; ++ch) {
        EXPECT_NEAR(e1[ch], kPi * c, 1e-5 * kPi * c);
        EXPECT_NEAR(e2[ch], kPi * c, 1e-5 * kPi * c);
      }
    }
  }
  // The angular map of the same constant environment.
  lp::Image ang(256, 256);
  std::fill(ang.rgb.begin(), ang.rgb.end(), c);
  const Sh9 La = projectImage(ang, lp::Layout::Angular);
  EXPECT_NEAR(La.c[0].x, 4 * kPi * 0.282095 * c, 1e-5 * 4 * kPi * 0.282095 * c);
  for (int k = 1; k < 9; ++k) EXPECT_NEAR(La.c[k].x, 0.0, 1e-4 * La.c[0].x) << "k=" << k;
}

// Basis sum and quadratic form (R&H eq. 12) are the same function of n.
TEST(ShCore, QuadraticFormEqualsBasisSum) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    Sh9 L;
    for (auto& v : L.c) v = {u(rng), u(rng), u(rng)};
    const auto m = lp::irradianceMatrices(L);
    for (int n = 0; n < 100; ++n) {
      const glm::vec3 nrm = randomUnit(rng);
      const glm::vec3 a = lp::evalIrradiance(L, nrm), b = lp::evalIrradianceQuadratic(m, nrm);
      // Independent: sum_lm A_l L_lm Y_lm(n) in float64 with exact normalisations.
      const auto y = refBasis(std::acos(double(nrm.z)), std::atan2(double(nrm.y), double(nrm.x)));
      for (int ch = 0; ch < 3; ++ch) {
        double ref = 0;
        for (int k = 0; k < 9; ++k) {
          const int l = lp::shBand(k);
          const double A = l == 0 ? kPi : (l == 1 ? 2 * kPi / 3 : kPi / 4);
          ref += A * L.c[k][ch] * y[k];
        }
        EXPECT_NEAR(a[ch], ref, 2e-5) << "basis sum";
        EXPECT_NEAR(b[ch], ref, 2e-5) << "quadratic form";
      }
    }
  }
}

// The equirect projection against a float64 loop written here by another path: each pixel's
// basis integral by 4x4-point Gauss-Legendre quadrature in (cos t, p), the spherical-coordinate
// basis, double accumulation. (The projector uses closed-form antiderivatives instead.)
TEST(ShCore, ProjectionMatchesFloat64Reference) {
  const int w = 160, h = 80;
  const lp::Image img = randomImage(w, h, 5.0f, 4);
  const Sh9 L = projectImage(img, lp::Layout::Equirect);
  const double gx[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                        0.8611363115940526};
  const double gw[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                        0.3478548451374538};
  std::array<double, 27> ref{};
  for (int i = 0; i < h; ++i) {
    const double u0 = std::cos(kPi * i / h), u1 = std::cos(kPi * (i + 1) / h);
    for (int j = 0; j < w; ++j) {
      const double p0 = 2 * kPi * j / w, p1 = 2 * kPi * (j + 1) / w;
      std::array<double, 9> integral{};
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) {
          const double uc = 0.5 * (u0 + u1) + 0.5 * (u0 - u1) * gx[a];
          const double pc = 0.5 * (p0 + p1) + 0.5 * (p1 - p0) * gx[b];
          const auto y = refBasis(std::acos(uc), pc);
          const double wgt = gw[a] * gw[b] * 0.25 * (u0 - u1) * (p1 - p0);
          for (int k = 0; k < 9; ++k) integral[k] += wgt * y[k];
        }
      for (int k = 0; k < 9; ++k)
        for (int ch = 0; ch < 3; ++ch) ref[3 * k + ch] += img.pixel(j, i)[ch] * integral[k];
    }
  }
  // 1e-5 of L00: float32 row sums against float64; the basis constants differ by < 1e-6.
  for (int k = 0; k < 9; ++k)
    for (int ch = 0; ch < 3; ++ch)
      EXPECT_NEAR(L.c[k][ch], ref[3 * k + ch], 1e-5 * ref[0]) << lp::kShNames[k] << " ch " << ch;
}

// The generic per-sample path (used for non-equirect layouts) agrees with the exact equirect
// path to the midpoint-rule error O(1/H^2).
TEST(ShCore, SamplePathAgreesWithExactEquirect) {
  const int w = 512, h = 256;
  const lp::Image img = randomImage(w, h, 2.0f, 7);
  const Sh9 a = lp::project(lp::PanoramaView::rgbF32(img.rgb.data(), w, h));
  const auto s = lp::layoutSamples(lp::Layout::Equirect, w, h);
  const Sh9 b = lp::projectSamples(img.rgb.data(), 3, s.data(), s.size());
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(a.c[k].x, b.c[k].x, 2e-5 * a.c[0].x) << lp::kShNames[k];
}

// A band-limited environment L(w) = sum a_k Y_k(w) has coefficients exactly a_k.
TEST(ShCore, BandLimitedEnvironmentRecoversItsCoefficients) {
  const std::array<double, 9> a = {2.0, 0.3, -0.5, 0.25, 0.1, -0.2, 0.15, 0.05, -0.12};
  const int w = 512, h = 256;
  lp::Image img(w, h);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) {
      const auto y = refBasis(kPi * (i + 0.5) / h, 2 * kPi * (j + 0.5) / w);
      double v = 0;
      for (int k = 0; k < 9; ++k) v += a[k] * y[k];
      float* p = img.pixel(j, i);
      p[0] = p[1] = p[2] = float(v);
    }
  const Sh9 L = projectImage(img, lp::Layout::Equirect);
  // The image holds L at pixel centres, not pixel averages: O(1/H^2), 1e-4 of L00 at H = 256.
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(L.c[k].y, a[k], 1e-4 * a[0]) << lp::kShNames[k];
}

// A small bright disc: coefficients Y_lm(dir) * power; the paper's worst case error 3/32.
TEST(ShCore, DirectionalLight) {
  const glm::dvec3 dir = glm::normalize(glm::dvec3(0.3, -0.5, 0.6));
  double power = 0;
  const double radius = 1.5 * kPi / 180;
  const lp::Image img = lpt::discEquirect(2048, 1024, dir, radius, 100.0f, &power);
  const Sh9 L = projectImage(img, lp::Layout::Equirect);
  const auto y = refBasis(std::acos(dir.z), std::atan2(dir.y, dir.x));
  // A uniform cap of half-angle d averages Y_lm to Y_lm(centre) (P_{l-1} - P_{l+1})(cos d) /
  // ((2l+1)(1 - cos d)): 1, 0.99983, 0.99949 for l = 0, 1, 2 here. What remains is the
  // staircase of the disc's pixels (~500 of them): tolerance 0.1% of L00.
  const double cd = std::cos(radius);
  const double capFactor[3] = {1.0, (1 + cd) / 2, (cd * (1 + cd)) / 2};
  for (int k = 0; k < 9; ++k)
    EXPECT_NEAR(L.c[k].x, y[k] * power * capFactor[lp::shBand(k)], 1e-3 * 0.282095 * power)
        << lp::kShNames[k];
}

// minIrradiance against a dense random search.
TEST(ShCore, MinimumIrradianceDiagnostic) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  for (int trial = 0; trial < 10; ++trial) {
    Sh9 L;
    L.c[0] = glm::vec3(1.0f);
    for (int k = 1; k < 9; ++k) L.c[k] = {u(rng), u(rng), u(rng)};
    const lp::MinIrradiance mn = lp::minIrradiance(L);
    glm::vec3 dense(INFINITY);
    for (int n = 0; n < 200000; ++n)
      dense = glm::min(dense, lp::evalIrradiance(L, randomUnit(rng)));
    for (int ch = 0; ch < 3; ++ch) {
      EXPECT_LE(mn.value[ch], dense[ch] + 1e-6f);
      EXPECT_GT(mn.value[ch], dense[ch] - 2e-3f);  // random search is coarser than the solver
      EXPECT_NEAR(lp::evalIrradiance(L, mn.normal[ch])[ch], mn.value[ch], 1e-5f);
    }
  }
}

TEST(ShCore, HannWindow) {
  const auto w = lp::hannWindow(4.0f);
  EXPECT_NEAR(w.sigma1, 0.5 * (1 + std::cos(kPi / 4)), 1e-6);
  EXPECT_NEAR(w.sigma2, 0.5, 1e-6);
  EXPECT_EQ(lp::hannWindow(2.0f).sigma2, 0.0f);
  const auto none = lp::hannWindow(INFINITY);
  EXPECT_EQ(none.sigma1, 1.0f);
  EXPECT_EQ(none.sigma2, 1.0f);
}

// auto finds the mildest window that removes ringing: it is non-negative, and 3% milder is not.
TEST(ShCore, AutoWindowIsMildestNonNegative) {
  const glm::vec3 dir = glm::normalize(glm::vec3(0.2f, 0.7f, -0.3f));
  Sh9 L;  // an ideal directional light of power 1
  const auto y = lp::shBasis(dir);
  for (int k = 0; k < 9; ++k) L.c[k] = glm::vec3(y[k]);
  ASSERT_LT(lp::minIrradiance(L).minOfChannels(), -0.01f);
  const lp::AutoWindow aw = lp::autoWindow(L);
  ASSERT_TRUE(std::isfinite(aw.width));
  EXPECT_GE(lp::minIrradiance(lp::applyWindow(L, aw.window)).minOfChannels(), -1e-6f);
  EXPECT_LT(lp::minIrradiance(lp::applyWindow(L, lp::hannWindow(aw.width * 1.03f))).minOfChannels(),
            0.0f);
  // A constant environment needs none.
  Sh9 c;
  c.c[0] = glm::vec3(1.0f);
  EXPECT_TRUE(std::isinf(lp::autoWindow(c).width));
}

// cmgen's window against cmgen's own formula on a case solved in closed form. An ideal
// directional light has the zonal irradiance E(t) = 1/4 + (s1 / 2) t + (5 s2 / 32) (3 t^2 - 1)
// at cos angle t; its minimum is at t = -8 s1 / (15 s2), or at t = -1 when that lies beyond.
// cmgen's cutoff is the largest whose sinc^4 window makes it >= 0, less up to 0.1 band per
// channel: each channel's bisection starts below the last one's result and stops within 0.1.
TEST(ShCore, CmgenWindowMatchesCmgensFormula) {
  auto sinc4 = [](int l, double c) {
    const double x = kPi * l / c;
    return std::pow(std::sin(x) / x, 4.0);
  };
  const auto w = lp::sincWindow(6.0f);
  EXPECT_NEAR(w.sigma1, sinc4(1, 6.0), 1e-6);
  EXPECT_NEAR(w.sigma2, sinc4(2, 6.0), 1e-6);
  EXPECT_EQ(lp::sincWindow(2.0f).sigma2, 0.0f);  // l >= cutoff: 0

  auto zonalMin = [&](double c) {
    const double s1 = sinc4(1, c), s2 = sinc4(2, c);
    const double t = std::max(-1.0, -8.0 * s1 / (15.0 * s2));
    return 0.25 + 0.5 * s1 * t + 5.0 / 32.0 * s2 * (3 * t * t - 1);
  };
  double lo = 3, hi = 13;  // the closed form's root, to 1e-9
  while (hi - lo > 1e-9) ((zonalMin(0.5 * (lo + hi)) < 0) ? hi : lo) = 0.5 * (lo + hi);
  const glm::vec3 dir = glm::normalize(glm::vec3(-0.4f, 0.5f, 0.6f));
  Sh9 L;
  const auto y = lp::shBasis(dir);
  for (int k = 0; k < 9; ++k) L.c[k] = glm::vec3(y[k]);
  const lp::CmgenWindow cw = lp::cmgenWindow(L);
  EXPECT_LE(cw.cutoff, lo + 1e-4);
  EXPECT_GT(cw.cutoff, lo - 0.3);
  EXPECT_GE(lp::minIrradiance(lp::applyWindow(L, cw.window)).minOfChannels(), -1e-6f);

  // Already non-negative: cmgen still windows, each channel a step below 13 bands; cmgen's own
  // output on such a map (Grace) is band 1 x0.960 and band 2 x0.850.
  Sh9 c;
  c.c[0] = glm::vec3(1.0f);
  const lp::CmgenWindow none = lp::cmgenWindow(c);
  EXPECT_NEAR(none.window.sigma1, 0.960, 5e-4);
  EXPECT_NEAR(none.window.sigma2, 0.850, 5e-4);
}

}  // namespace

namespace {

// R&H's eq. 12 constants, as the paper prints them, against the ones the core folds from A_l
// and the basis constants: an L with only coefficient k set puts c into known entries of M.
TEST(ShCore, QuadraticFormConstantsAreThePapers) {
  auto matrixOf = [](int k) {
    Sh9 L;
    L.c[k] = lp::Rgb(1.0f);
    return lp::irradianceMatrices(L)[0];
  };
  EXPECT_NEAR(matrixOf(8)[0][0], 0.429043, 1e-6);   // c1 L22
  EXPECT_NEAR(matrixOf(3)[3][0], 0.511664, 1e-6);   // c2 L11
  EXPECT_NEAR(matrixOf(6)[2][2], 0.743125, 1e-6);   // c3 L20
  EXPECT_NEAR(matrixOf(0)[3][3], 0.886227, 1e-6);   // c4 L00
  EXPECT_NEAR(-matrixOf(6)[3][3], 0.247708, 1e-6);  // c5 L20
}

// The SIMD paths: listed, forced, refused in one line when unknown or absent, and each one gives
// the float64 answer on every pixel format (the whole accuracy suite also runs once per path:
// tests/scripts/every_simd_path.sh).
TEST(Simd, PathsAreListedAndForced) {
  const auto paths = lp::simd::available();
  ASSERT_FALSE(paths.empty());
  EXPECT_EQ(paths.front(), "scalar");
  if (const char* env = std::getenv("LIVEPROBE_SIMD")) {
    EXPECT_EQ(lp::simd::current(), std::string(env) == "native" ? paths.back() : env);
  }
  const std::string before = lp::simd::current();
  try {
    lp::simd::select("sse9");
    ADD_FAILURE() << "an unknown path was accepted";
  } catch (const lp::Error& e) {
    EXPECT_NE(std::string(e.what()).find("LIVEPROBE_SIMD=sse9: unknown path"), std::string::npos)
        << e.what();
  }
  for (const char* absent : {"avx2", "avx512", "neon"})
    if (std::find(paths.begin(), paths.end(), absent) == paths.end()) {
      EXPECT_THROW(lp::simd::select(absent), lp::Error) << absent;
    }
  lp::simd::select("native");
  EXPECT_EQ(lp::simd::current(), paths.back());
  lp::simd::select(before);
}

TEST(Simd, EveryPathMatchesFloat64OnEveryFormat) {
  // Odd widths leave a tail in every row; a fisheye exercises the per-pixel weights.
  const int w = 262, h = 131;
  const lp::Image img = randomImage(w, h, 3.0f, 11);
  std::vector<std::uint8_t> u8(img.rgb.size());
  std::vector<float> lut(256), fromU8(img.rgb.size());
  for (int i = 0; i < 256; ++i) lut[i] = 0.01f * float(i);
  std::mt19937 rng(5);
  for (std::size_t i = 0; i < u8.size(); ++i) u8[i] = std::uint8_t(rng());
  for (std::size_t i = 0; i < u8.size(); i += 3)  // the view is BGR: RGB floats for the reference
    for (int c = 0; c < 3; ++c) fromU8[i + c] = lut[u8[i + 2 - c]];
  std::vector<std::uint16_t> f16(img.rgb.size());
  std::vector<float> fromF16(img.rgb.size());
  for (std::size_t i = 0; i < f16.size(); ++i) {
    const int q = int(rng() % 1024);
    f16[i] = std::uint16_t(0x3C00 | q);  // 1 + q/1024, exact in binary16
    fromF16[i] = 1.0f + float(q) / 1024.0f;
  }
  const std::string before = lp::simd::current();
  for (const std::string& path : lp::simd::available()) {
    lp::simd::select(path);
    lp::ThreadPool two(2);
    for (lp::Layout layout : {lp::Layout::Equirect, lp::Layout::DualFisheye}) {
      const lp::Projector proj(layout, layout == lp::Layout::DualFisheye ? 2 * h : w, h);
      const auto& s = proj.samples();
      auto reference = [&](const std::vector<float>& rgb) {  // float64 sum over the same weights
        std::array<double, 27> ref{};
        for (std::size_t i = 0; i < s.size(); ++i) {
          const auto y = lp::shBasis(s[i].dir);
          for (int k = 0; k < 9; ++k)
            for (int c = 0; c < 3; ++c)
              ref[3 * k + c] += double(rgb[3 * i + c]) * y[k] * s[i].solidAngle;
        }
        return ref;
      };
      struct Case {
        const char* name;
        lp::PanoramaView view;
        const std::vector<float>* truth;
      };
      const Case cases[] = {
          {"f32", lp::PanoramaView::rgbF32(img.rgb.data(), w, h, layout), &img.rgb},
          {"u8", lp::PanoramaView::bgrU8(u8.data(), w, h, lut.data(), layout), &fromU8},
          {"f16", lp::PanoramaView::rgbF16(f16.data(), w, h, layout), &fromF16}};
      for (const Case& c : cases) {
        const auto ref = reference(*c.truth);
        for (lp::Executor* ex :
             {static_cast<lp::Executor*>(nullptr), static_cast<lp::Executor*>(&two)}) {
          const Sh9 L = proj.project(c.view, ex);
          // Equirect integrates the basis over each pixel, the reference samples it at the
          // centre: they differ by the midpoint rule's O(1/H^2), under 3e-4 of L00 here.
          const double tol = (layout == lp::Layout::Equirect ? 3e-4 : 1e-5) * ref[0];
          for (int k = 0; k < 9; ++k)
            for (int ch = 0; ch < 3; ++ch)
              EXPECT_NEAR(L.c[k][ch], ref[3 * k + ch], tol)
                  << path << " " << lp::layoutName(layout) << " " << c.name << " "
                  << lp::kShNames[k] << " ch " << ch << (ex ? " 2 threads" : "");
        }
      }
    }
  }
  lp::simd::select(before);
}

TEST(Simd, RowPeaksAreEachRowsLargestValueOnEveryPath) {
  // The row peaks light extraction starts from: equirect frames take them inside the projection
  // kernel (floats) or from the row's codes (8-bit through a non-decreasing table); other layouts
  // and a table that is not monotonic from the decoded row. Each must be the row's largest value.
  const int w = 262, h = 131;
  const lp::Image img = randomImage(w, h, 3.0f, 17);
  std::mt19937 rng(23);
  std::vector<std::uint8_t> u8(img.rgb.size());
  for (auto& c : u8) c = std::uint8_t(rng() % 200);  // each row's largest code differs
  std::vector<float> rising(256), falling(256);
  for (int i = 0; i < 256; ++i) rising[i] = 0.01f * float(i), falling[i] = 0.01f * float(255 - i);
  const std::string before = lp::simd::current();
  for (const std::string& path : lp::simd::available()) {
    lp::simd::select(path);
    lp::ThreadPool two(2);
    for (lp::Layout layout : {lp::Layout::Equirect, lp::Layout::DualFisheye}) {
      const int width = layout == lp::Layout::DualFisheye ? 2 * h : w;
      const lp::Projector proj(layout, width, h);
      struct Case {
        const char* name;
        lp::PanoramaView view;
        std::vector<float> truth;  // per row, the largest linear channel value
      };
      std::vector<Case> cases;
      auto rowMax = [&](auto value) {
        std::vector<float> m(std::size_t(h), -INFINITY);
        for (int r = 0; r < h; ++r)
          for (int q = 0; q < 3 * width; ++q) m[r] = std::max(m[r], value(3 * r * width + q));
        return m;
      };
      cases.push_back({"f32", lp::PanoramaView::rgbF32(img.rgb.data(), width, h, layout),
                       rowMax([&](int q) { return img.rgb[q]; })});
      cases.push_back({"u8 rising",
                       lp::PanoramaView::bgrU8(u8.data(), width, h, rising.data(), layout),
                       rowMax([&](int q) { return rising[u8[q]]; })});
      cases.push_back({"u8 falling",
                       lp::PanoramaView::bgrU8(u8.data(), width, h, falling.data(), layout),
                       rowMax([&](int q) { return falling[u8[q]]; })});
      for (const Case& c : cases)
        for (lp::Executor* ex :
             {static_cast<lp::Executor*>(nullptr), static_cast<lp::Executor*>(&two)}) {
          std::vector<float> peaks;
          proj.project(c.view, ex, &peaks);
          ASSERT_EQ(peaks.size(), std::size_t(h));
          for (int r = 0; r < h; ++r)
            ASSERT_EQ(peaks[r], c.truth[r]) << path << " " << lp::layoutName(layout) << " "
                                            << c.name << " row " << r << (ex ? " 2 threads" : "");
        }
    }
  }
  lp::simd::select(before);
}

TEST(ShCore, AddPixelsIsWhatProjectCounts) {
  // Projector::addPixels gives the coefficients of a few pixels with project()'s own weights:
  // adding every row of a frame in two runs gives the frame's projection, and the float64 sum
  // over the pixels' directions and solid angles (as ProjectionMatchesFloat64Reference).
  const int h = 64;
  const lp::Image img = randomImage(2 * h, h, 2.0f, 29);
  for (lp::Layout layout : {lp::Layout::Equirect, lp::Layout::DualFisheye}) {
    const int w = 2 * h;
    const lp::Projector proj(layout, w, h);
    const Sh9 whole = proj.project(lp::PanoramaView::rgbF32(img.rgb.data(), w, h, layout));
    std::array<glm::dvec3, 9> sums{};
    std::vector<lp::Rgb> row(static_cast<std::size_t>(w));
    for (int r = 0; r < h; ++r) {
      for (int j = 0; j < w; ++j)
        row[j] = lp::Rgb(img.rgb[3 * (r * w + j)], img.rgb[3 * (r * w + j) + 1],
                         img.rgb[3 * (r * w + j) + 2]);
      const int split = 1 + r % (w - 1);  // two runs of varying lengths
      proj.addPixels(std::size_t(r), 0, row.data(), std::size_t(split), sums);
      proj.addPixels(std::size_t(r), std::size_t(split), row.data() + split, std::size_t(w - split),
                     sums);
    }
    const auto& s = proj.samples();
    std::array<glm::dvec3, 9> ref{};
    for (std::size_t i = 0; i < s.size(); ++i) {
      const auto y = lp::shBasis(s[i].dir);
      const glm::dvec3 v(img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2]);
      for (int k = 0; k < 9; ++k) ref[k] += v * double(y[k]) * double(s[i].solidAngle);
    }
    const double l00 = whole.c[0].x;
    // Equirect integrates the basis over each pixel, the reference samples it at the centre.
    const double refTol = (layout == lp::Layout::Equirect ? 3e-3 : 1e-5) * l00;
    for (int k = 0; k < 9; ++k)
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(sums[k][c], whole.c[k][c], 1e-6 * l00)
            << lp::layoutName(layout) << " " << lp::kShNames[k];
        EXPECT_NEAR(sums[k][c], ref[k][c], refTol)
            << lp::layoutName(layout) << " " << lp::kShNames[k];
      }
  }
}

}  // namespace
