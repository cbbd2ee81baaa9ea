// Tier 2: panorama layouts map pixels to the documented directions with exact solid angles.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "liveprobe/sh/error.h"
#include "liveprobe/sh/image.h"
#include "liveprobe/sh/layout.h"

namespace {

constexpr double kPi = std::numbers::pi;

double sumSolidAngle(const std::vector<lp::SphereSample>& s) {
  double t = 0;
  for (const auto& x : s) t += x.solidAngle;
  return t;
}

TEST(Layout, EquirectSolidAnglesSumTo4PiAtAnyAspect) {
  for (auto [w, h] :
       {std::pair{300, 300}, std::pair{1024, 512}, std::pair{7, 3}, std::pair{1920, 1080}})
    EXPECT_NEAR(sumSolidAngle(lp::layoutSamples(lp::Layout::Equirect, w, h)), 4 * kPi, 1e-4)
        << w << "x" << h;
}

TEST(Layout, EquirectDirections) {
  const int w = 8, h = 4;
  const auto s = lp::layoutSamples(lp::Layout::Equirect, w, h);
  // Row 0 is next to +z; column j at p = 2 pi (j + 0.5) / W measured from +x towards +y.
  const double t = kPi * 0.5 / h, p = 2 * kPi * 0.5 / w;
  EXPECT_NEAR(s[0].dir.z, std::cos(t), 1e-6);
  EXPECT_NEAR(s[0].dir.x, std::sin(t) * std::cos(p), 1e-6);
  EXPECT_NEAR(s[0].dir.y, std::sin(t) * std::sin(p), 1e-6);
  EXPECT_LT(s[(h - 1) * w].dir.z, -0.9f);  // bottom row near -z
  // Row 1, column 2: t = 3 pi / 8, p = 5 pi / 8.
  EXPECT_NEAR(s[1 * w + 2].dir.x, std::sin(3 * kPi / 8) * std::cos(5 * kPi / 8), 1e-6);
  EXPECT_NEAR(s[1 * w + 2].dir.y, std::sin(3 * kPi / 8) * std::sin(5 * kPi / 8), 1e-6);
}

TEST(Layout, AngularSolidAnglesAreExact) {
  const int w = 256;
  const auto s = lp::layoutSamples(lp::Layout::Angular, w, w);
  EXPECT_NEAR(sumSolidAngle(s), 4 * kPi, 1e-4);
  // Centre pixel: Jacobian (2 pi / W)^2 sin t / t with t ~ 0.
  const auto& c = s[(w / 2) * w + w / 2];
  const double t = kPi * std::sqrt(0.5) / (w / 2.0);
  EXPECT_NEAR(c.solidAngle, std::pow(2 * kPi / w, 2) * std::sin(t) / t, 1e-4 * c.solidAngle);
  // Pixels with r < 1/2 are the hemisphere around the centre direction: 2 pi sr, up to the
  // staircase of the pixel boundary (about 1/W relative).
  double hemi = 0;
  for (int i = 0; i < w; ++i)
    for (int j = 0; j < w; ++j) {
      const double u = (j + 0.5 - w / 2.0) / (w / 2.0), v = (w / 2.0 - i - 0.5) / (w / 2.0);
      if (u * u + v * v < 0.25) hemi += s[i * w + j].solidAngle;
    }
  EXPECT_NEAR(hemi, 2 * kPi, 2 * kPi * 2.0 / w);
  // Corners are outside the disc.
  EXPECT_EQ(s[0].solidAngle, 0.0f);
}

// The documented world frame of the angular map: centre -> -x, top -> +z, right -> -y.
TEST(Layout, AngularDirections) {
  const int w = 200;
  const auto s = lp::layoutSamples(lp::Layout::Angular, w, w);
  auto dirAt = [&](double u, double v) {
    const int j = int(std::floor((u + 1) * w / 2)), i = int(std::floor((1 - v) * w / 2));
    return s[i * w + j].dir;
  };
  const glm::vec3 centre = dirAt(0.0, 0.0), top = dirAt(0.0, 0.5), right = dirAt(0.5, 0.0),
                  back = dirAt(0.0, 0.995);
  EXPECT_LT(centre.x, -0.999f);
  EXPECT_GT(top.z, 0.99f);     // r = 1/2 -> t = pi/2, straight up
  EXPECT_LT(right.y, -0.99f);  // image right -> -y
  EXPECT_GT(back.x, 0.99f);    // the rim is the direction behind the map's centre: +x
  EXPECT_NEAR(glm::length(centre), 1.0f, 1e-6f);
}

TEST(Layout, MismatchedFrameIsRejected) {
  EXPECT_FALSE(lp::layoutMismatch(lp::Layout::Angular, 640, 480).empty());
  EXPECT_TRUE(lp::layoutMismatch(lp::Layout::Angular, 640, 640).empty());
  EXPECT_THROW(lp::layoutSamples(lp::Layout::Angular, 640, 480), lp::Error);
  EXPECT_THROW(lp::parseLayout("cubemap-ish"), lp::Error);
}

// Resampling an equirect environment into an angular map (by the documented mapping, written
// again here) gives the same coefficients.
TEST(Layout, AngularAgreesWithEquirect) {
  const int we = 512, he = 256, wa = 512;
  lp::Image eq(we, he);
  // A smooth but not band-limited sky: sun-ish lobe plus gradient.
  auto radiance = [](glm::dvec3 d) {
    const glm::dvec3 sun = glm::normalize(glm::dvec3(-0.4, 0.3, 0.5));
    return glm::dvec3(0.2 + 0.3 * std::max(0.0, d.z)) +
           glm::dvec3(4, 3, 2) * std::pow(std::max(0.0, glm::dot(d, sun)), 8.0);
  };
  for (int i = 0; i < he; ++i)
    for (int j = 0; j < we; ++j) {
      const double t = kPi * (i + 0.5) / he, p = 2 * kPi * (j + 0.5) / we;
      const auto L = radiance({std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)});
      float* px = eq.pixel(j, i);
      px[0] = float(L.x), px[1] = float(L.y), px[2] = float(L.z);
    }
  lp::Image ang(wa, wa);
  for (int i = 0; i < wa; ++i)
    for (int j = 0; j < wa; ++j) {
      const double u = (j + 0.5 - wa / 2.0) / (wa / 2.0), v = (wa / 2.0 - i - 0.5) / (wa / 2.0);
      const double r = std::sqrt(u * u + v * v);
      if (r > 1) continue;
      const double t = kPi * r, p = std::atan2(v, u);
      const glm::dvec3 l(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
      const auto L = radiance({-l.z, -l.x, l.y});
      float* px = ang.pixel(j, i);
      px[0] = float(L.x), px[1] = float(L.y), px[2] = float(L.z);
    }
  auto project = [](const lp::Image& img, lp::Layout layout) {
    const auto s = lp::layoutSamples(layout, img.width, img.height);
    return lp::projectSamples(img.rgb.data(), 3, s.data(), s.size());
  };
  const lp::Sh9 a = project(eq, lp::Layout::Equirect), b = project(ang, lp::Layout::Angular);
  for (int k = 0; k < 9; ++k)
    for (int ch = 0; ch < 3; ++ch)
      EXPECT_NEAR(a.c[k][ch], b.c[k][ch], 2e-3 * a.c[0][ch]) << lp::kShNames[k];
}

}  // namespace
