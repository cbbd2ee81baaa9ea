// Sun and sky (liveprobe/sh/lights.h), each against an independent truth: the disc light's
// irradiance against numerical integration over the disc; a rendered sky with a disc sun of known
// direction, radius and power in every layout; a sky with no sun left untouched; and the moving
// sun of the synthetic source tracked frame by frame.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <random>

#include "layout_dirs.h"
#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/capture/open_source.h"
#include "liveprobe/capture/pipeline.h"
#include "liveprobe/exchange/coeffs_io.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/sh/image.h"
#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/projector.h"
#include "test_util.h"

namespace {

constexpr double kPi = std::numbers::pi;
using glm::dvec3;

double angleDeg(dvec3 a, dvec3 b) {
  return glm::degrees(
      std::acos(std::clamp(glm::dot(glm::normalize(a), glm::normalize(b)), -1.0, 1.0)));
}

// A uniform disc's clamped-cosine irradiance, by midpoint quadrature over the disc in its own
// polar coordinates (independent of the closed form).
double discIrradianceByQuadrature(double radius, double beta, double radiance) {
  const int nr = 400, np = 800;
  const dvec3 n(std::sin(beta), 0, std::cos(beta));  // the light is at +z
  double e = 0;
  for (int i = 0; i < nr; ++i) {
    const double t0 = radius * i / nr, t1 = radius * (i + 1) / nr, t = 0.5 * (t0 + t1);
    const double ring = (std::cos(t0) - std::cos(t1)) * 2 * kPi / np;
    for (int j = 0; j < np; ++j) {
      const double p = 2 * kPi * (j + 0.5) / np;
      const dvec3 w(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
      e += radiance * std::max(0.0, glm::dot(n, w)) * ring;
    }
  }
  return e;
}

TEST(Lights, DiscIrradianceIsTheExactClampedCosine) {
  for (const double radiusDeg : {0.0, 0.27, 0.5, 1.0, 5.0, 20.0}) {
    const double a = glm::radians(radiusDeg);
    const double omega = 2 * kPi * (1 - std::cos(a));
    lp::Light light;
    light.dir = {0.0f, 0.0f, 1.0f};
    light.angularRadius = float(a);
    light.power = glm::vec3(2.0f);
    for (const double betaDeg :
         {0.0, 30.0, 80.0, 88.0, 89.9, 90.0, 90.1, 90.2, 93.0, 105.0, 120.0}) {
      const double beta = glm::radians(betaDeg);
      const double truth = radiusDeg == 0.0 ? 2.0 * std::max(0.0, std::cos(beta))
                                            : discIrradianceByQuadrature(a, beta, 2.0 / omega);
      const glm::vec3 n(float(std::sin(beta)), 0.0f, float(std::cos(beta)));
      EXPECT_NEAR(lp::lightIrradiance(light, n).x, truth, 2e-4 * 2.0)
          << "radius " << radiusDeg << " beta " << betaDeg;
    }
  }
}

// A smooth sky (linear in the direction: exactly bands 0 and 1) and a disc sun.
struct SunSky {
  dvec3 sunDir;
  double radius;  ///< radians
  dvec3 sunRadiance;
  dvec3 sky(dvec3 d) const {
    return {0.5 + 0.3 * d.z, 0.6 + 0.2 * d.z + 0.1 * d.y, 0.9 + 0.1 * d.x};
  }
  double omega() const { return 2 * kPi * (1 - std::cos(radius)); }
  dvec3 power() const { return sunRadiance * omega(); }
};

// Renders the sky (and the sun when `withSun`) into a layout: pixels near the sun are the average
// of 8x8 sub-samples, so the disc's edge is anti-aliased and its power right to well under 1%;
// the others (and the sky-only image alike) are sampled at their centre.
lp::Image render(const SunSky& s, int w, int h, const lpt::DirAt& dirAt, bool withSun) {
  lp::Image img(w, h);
  const double cosR = std::cos(s.radius), cosNear = std::cos(s.radius + glm::radians(4.0));
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) {
      dvec3 sum(0);
      int n = 0;
      const auto centre = dirAt(j + 0.5, i + 0.5);
      const int sub = centre && glm::dot(*centre, s.sunDir) >= cosNear ? 8 : 1;
      for (int a = 0; a < sub; ++a)
        for (int b = 0; b < sub; ++b)
          if (auto d = dirAt(j + (b + 0.5) / sub, i + (a + 0.5) / sub)) {
            sum += s.sky(*d);
            if (withSun && glm::dot(*d, s.sunDir) >= cosR) sum += s.sunRadiance;
            ++n;
          }
      if (n) {
        float* p = img.pixel(j, i);
        sum /= double(n);
        p[0] = float(sum.x), p[1] = float(sum.y), p[2] = float(sum.z);
      }
    }
  return img;
}

struct LayoutCase {
  std::string name;
  lp::LayoutSpec spec;
  int w, h;
  lpt::DirAt dirs;
};

std::vector<LayoutCase> everyLayout() {
  lp::LayoutSpec ball(lp::Layout::MirrorBall);
  ball.circle = {300.0f, 250.0f, 220.0f};
  return {{"equirect", lp::Layout::Equirect, 1024, 512, lpt::equirectDirs(1024, 512)},
          {"angular", lp::Layout::Angular, 512, 512, lpt::angularDirs(512)},
          {"mirrorball", ball, 640, 480, lpt::mirrorBallDirs(300, 250, 220)},
          {"cube", lp::Layout::Cube, 512, 384, lpt::cubeCrossDirs(128, false)},
          {"fisheye", lp::Layout::DualFisheye, 1024, 512, lpt::dualFisheyeDirs(1024, 512, 190)}};
}

// The sun is found in every layout: direction within 0.25 degrees, power within 1%, radius within
// 20%, and what is left is the sky's coefficients within 1e-3 of L00.
TEST(Lights, DiscSunInEveryLayout) {
  // One sun well inside every layout's view, one in the fisheye lenses' overlap (|x| < 0.087).
  for (const dvec3 dir :
       {glm::normalize(dvec3(-0.5, -0.4, 0.6)), glm::normalize(dvec3(0.03, 0.8, 0.3))}) {
    SunSky s{dir, glm::radians(2.0), {}};
    s.sunRadiance = dvec3(4.0, 3.5, 3.0) / s.omega();  // about half of the whole map's power
    for (const LayoutCase& c : everyLayout()) {
      SCOPED_TRACE(c.name + " sun (" + std::to_string(dir.x) + ", " + std::to_string(dir.y) + ")");
      const lp::Image sunny = render(s, c.w, c.h, c.dirs, true);
      const lp::Image sky = render(s, c.w, c.h, c.dirs, false);
      const auto view = lp::PanoramaView::rgbF32(sunny.rgb.data(), c.w, c.h, c.spec);
      const lp::LightSplit split = lp::projectWithLights(view, {});
      ASSERT_EQ(split.lights.size(), 1u);
      const lp::Light& l = split.lights[0];
      EXPECT_LT(angleDeg(dvec3(l.dir), dir), 0.25);
      for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(l.power[ch], s.power()[ch], 0.01 * s.power()[ch]);
      EXPECT_NEAR(glm::degrees(l.angularRadius), 2.0, 0.4);
      EXPECT_FALSE(l.clipped);
      const lp::Sh9 skyOnly =
          lp::project(lp::PanoramaView::rgbF32(sky.rgb.data(), c.w, c.h, c.spec));
      // And the lights' own coefficients make up the rest of the whole map's.
      const lp::Sh9 whole = lp::project(view), sum = split.residual + lp::lightsToSh(split.lights);
      for (int k = 0; k < lp::kShCount; ++k)
        for (int ch = 0; ch < 3; ++ch) {
          EXPECT_NEAR(split.residual.c[k][ch], skyOnly.c[k][ch], 1e-3 * skyOnly.c[0][ch])
              << lp::kShNames[k] << " ch " << ch;
          EXPECT_NEAR(sum.c[k][ch], whole.c[k][ch], 1e-3 * whole.c[0][ch])
              << lp::kShNames[k] << " ch " << ch;
        }
    }
  }
}

// A map with no compact source (a smooth sky, in every layout) has no light, and its coefficients
// are exactly the whole map's.
TEST(Lights, NoSunLeavesTheMapExactlyAsItIs) {
  SunSky s{dvec3(0, 0, 1), 0.0, dvec3(0)};
  for (const LayoutCase& c : everyLayout()) {
    const lp::Image sky = render(s, c.w / 2, c.h / 2,
                                 c.name == "mirrorball" ? lpt::mirrorBallDirs(150, 125, 110)
                                 : c.name == "equirect" ? lpt::equirectDirs(c.w / 2, c.h / 2)
                                 : c.name == "angular"  ? lpt::angularDirs(c.w / 2)
                                 : c.name == "cube"     ? lpt::cubeCrossDirs(64, false)
                                                    : lpt::dualFisheyeDirs(c.w / 2, c.h / 2, 190),
                                 false);
    lp::LayoutSpec spec = c.spec;
    if (c.name == "mirrorball") spec.circle = {150.0f, 125.0f, 110.0f};
    const auto view = lp::PanoramaView::rgbF32(sky.rgb.data(), sky.width, sky.height, spec);
    const lp::LightSplit split = lp::projectWithLights(view, {});
    EXPECT_TRUE(split.lights.empty()) << c.name;
    EXPECT_EQ(split.residual, lp::project(view)) << c.name;
  }
}

// Several lamps: --lights 3 finds three suns of different power, brightest first.
TEST(Lights, SeveralLights) {
  const dvec3 dirs[3] = {glm::normalize(dvec3(-1, 0.2, 0.3)), glm::normalize(dvec3(0.2, 1, 0.5)),
                         glm::normalize(dvec3(0.5, -0.6, 0.2))};
  const double powers[3] = {3.0, 2.0, 1.2};
  const int w = 1024, h = 512;
  const auto dirAt = lpt::equirectDirs(w, h);
  SunSky s{dirs[0], glm::radians(1.0), dvec3(0)};
  lp::Image img = render(s, w, h, dirAt, false);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j)
      for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b) {
          const dvec3 d = *dirAt(j + (b + 0.5) / 8, i + (a + 0.5) / 8);
          for (int k = 0; k < 3; ++k)
            if (glm::dot(d, dirs[k]) >= std::cos(s.radius))
              for (int ch = 0; ch < 3; ++ch)
                img.pixel(j, i)[ch] += float(powers[k] / s.omega() / 64);
        }
  lp::LightOptions o;
  o.maxLights = 3;
  const auto split = lp::projectWithLights(lp::PanoramaView::rgbF32(img.rgb.data(), w, h), o);
  ASSERT_EQ(split.lights.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_LT(angleDeg(dvec3(split.lights[k].dir), dirs[k]), 0.25) << k;
    EXPECT_NEAR(split.lights[k].power.y, powers[k], 0.01 * powers[k]) << k;
  }
}

// A stream's hysteresis (LightOptions::held): a sun at 4% of the map's luminance power, under the
// 5% a light needs, is no light alone, and is one where the frame before had a light within 5
// degrees of it (held down to half the share); a light elsewhere holds nothing. A FrameProcessor
// carries it from frame to frame: a sun at 6% and then at 4% is a light in both frames, and the
// 4% frame alone in a fresh processor is none.
TEST(Lights, ALightTheFrameBeforeHadIsHeldAtHalfTheShare) {
  const int w = 512, h = 256;
  const dvec3 sunDir = glm::normalize(dvec3(0.3, -0.5, 0.6));
  const double skyPower = 0.6004 * 4 * kPi;  // SunSky::sky's mean luminance is 0.6004
  auto frameAt = [&](double share) {
    SunSky s{sunDir, glm::radians(1.0), dvec3(0)};
    s.sunRadiance = dvec3(share * skyPower / (1 - share) / s.omega());
    return render(s, w, h, lpt::equirectDirs(w, h), true);
  };
  const lp::Image faint = frameAt(0.04), clear = frameAt(0.06);
  const auto view = lp::PanoramaView::rgbF32(faint.rgb.data(), w, h);
  lp::LightOptions o;
  EXPECT_TRUE(lp::projectWithLights(view, o).lights.empty());
  o.held = {glm::vec3(glm::normalize(sunDir + dvec3(0.03, 0, 0)))};  // 2 degrees off
  const auto held = lp::projectWithLights(view, o);
  ASSERT_EQ(held.lights.size(), 1u);
  EXPECT_NEAR(held.lights[0].share, 0.04, 0.004);
  EXPECT_LT(angleDeg(dvec3(held.lights[0].dir), sunDir), 0.25);
  o.held = {glm::vec3(-sunDir)};
  EXPECT_TRUE(lp::projectWithLights(view, o).lights.empty());

  auto frameOf = [&](const lp::Image& img) {
    auto f = std::make_shared<lp::Frame>();
    f->format = lp::PanoramaFormat::RgbF32;
    f->width = img.width, f->height = img.height;
    f->rgb = img.rgb;
    return f;
  };
  lp::FrameProcessor stream({lp::LayoutSpec(), lp::Photometry{}, std::nullopt, 1, {}});
  EXPECT_EQ(stream.run(frameOf(clear)).lighting.lights.size(), 1u);
  EXPECT_EQ(stream.run(frameOf(faint)).lighting.lights.size(), 1u);
  lp::FrameProcessor fresh({lp::LayoutSpec(), lp::Photometry{}, std::nullopt, 1, {}});
  EXPECT_TRUE(fresh.run(frameOf(faint)).lighting.lights.empty());
}

// The synthetic source's sun moves (a full turn in 20 s, bobbing in elevation): the extracted
// direction follows the generator's own sun every frame, within 0.5 degrees.
TEST(Lights, TracksTheSyntheticMovingSun) {
  const int w = 512, h = 256;
  std::vector<float> rgb;
  for (int f = 0; f < 40; ++f) {
    const double t = 0.5 * f;
    lp::renderSyntheticSky(w, h, t, rgb);
    const auto split = lp::projectWithLights(lp::PanoramaView::rgbF32(rgb.data(), w, h), {});
    ASSERT_EQ(split.lights.size(), 1u) << "t = " << t;
    EXPECT_LT(angleDeg(dvec3(split.lights[0].dir), dvec3(lp::syntheticSunDirection(t))), 0.5)
        << "t = " << t;
  }
}

// 8-bit frames: a source at the code maximum is clipped, its power a lower bound, and says so.
TEST(Lights, ClippedEightBitSunIsALowerBound) {
  const int w = 512, h = 256;
  std::vector<std::uint8_t> bgr(std::size_t(w) * h * 3, 10);  // a dark room, a lamp at 255
  const dvec3 sun = glm::normalize(dvec3(-1, 0.3, 0.5));
  const auto dirAt = lpt::equirectDirs(w, h);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j)
      if (glm::dot(*dirAt(j + 0.5, i + 0.5), sun) > std::cos(glm::radians(3.0)))
        for (int c = 0; c < 3; ++c) bgr[(std::size_t(i) * w + j) * 3 + c] = 255;
  float lut[256];
  for (int v = 0; v < 256; ++v) lut[v] = std::pow(v / 255.0f, 2.2f);
  const auto split = lp::projectWithLights(lp::PanoramaView::bgrU8(bgr.data(), w, h, lut), {});
  ASSERT_EQ(split.lights.size(), 1u);
  EXPECT_TRUE(split.lights[0].clipped);
  EXPECT_LT(angleDeg(dvec3(split.lights[0].dir), sun), 0.5);
}

// An 8-bit sun as a camera clips it: a plateau at 255 inside a bright aureole, so bright that
// 30% of the clipped value reaches far beyond 8 degrees. The core is then the clipped plateau, and
// the light (a lower bound, under 5% of the power here) is kept by the clipped rule (1%); the
// split still conserves the map. A clipped speck under 1% is no light.
TEST(Lights, ClippedSunInABrightAureoleIsFound) {
  const int w = 512, h = 256;
  const dvec3 sun = glm::normalize(dvec3(-1, 0.4, 0.6));
  const auto dirAt = lpt::equirectDirs(w, h);
  float lut[256];
  for (int v = 0; v < 256; ++v) lut[v] = lp::srgbToLinear(v / 255.0f);
  const auto frame = [&](double plateauDeg, double aureole, double decayDeg) {
    std::vector<std::uint8_t> bgr(std::size_t(w) * h * 3);
    for (int i = 0; i < h; ++i)
      for (int j = 0; j < w; ++j) {
        const double a =
            glm::degrees(std::acos(std::clamp(glm::dot(*dirAt(j + 0.5, i + 0.5), sun), -1.0, 1.0)));
        const double v =
            a <= plateauDeg ? 255.0 : 20.0 + aureole * std::exp(-(a - plateauDeg) / decayDeg);
        for (int c = 0; c < 3; ++c)
          bgr[(std::size_t(i) * w + j) * 3 + c] = std::uint8_t(std::min(255.0, std::round(v)));
      }
    return bgr;
  };
  const auto bright = frame(3.0, 180.0, 20.0);
  const auto view = lp::PanoramaView::bgrU8(bright.data(), w, h, lut);
  const auto split = lp::projectWithLights(view, {});
  ASSERT_EQ(split.lights.size(), 1u);
  EXPECT_TRUE(split.lights[0].clipped);
  EXPECT_LT(angleDeg(dvec3(split.lights[0].dir), sun), 0.5);
  EXPECT_GE(split.lights[0].share, 0.01f);
  EXPECT_LT(split.lights[0].share, 0.05f);  // kept by the clipped rule, not the 5% one
  // Residual + light is the whole map: exactly in L00 (the light's power is what the region
  // lost); in bands 1 and 2 up to the disc model of a light whose excess spreads over the
  // plateau and the aureole taken with it (1.3e-4 of L00 here).
  const lp::Sh9 whole = lp::project(view), sum = split.residual + lp::lightsToSh(split.lights);
  EXPECT_NEAR(sum.c[0].x, whole.c[0].x, 1e-5 * whole.c[0].x);
  for (int k = 1; k < lp::kShCount; ++k)
    EXPECT_NEAR(sum.c[k].x, whole.c[k].x, 2.5e-4 * whole.c[0].x) << lp::kShNames[k];
  const auto speck = frame(0.3, 0.0, 1.0);  // a clipped glint on a dark sky
  EXPECT_TRUE(
      lp::projectWithLights(lp::PanoramaView::bgrU8(speck.data(), w, h, lut), {}).lights.empty());
}

// --sun everywhere the coefficients go.

// `coeffs --sun`: the lights beside the coefficients, and the two together are the whole map's.
TEST(LightsCli, CoeffsJsonCarriesTheLights) {
  const std::string map = lpt::shellQuote(lpt::dataPath("equirect/pedestrian_overpass_1k.hdr"));
  const auto whole = lpt::runLiveprobe("coeffs " + map);
  const auto sun = lpt::runLiveprobe("coeffs " + map + " --sun");
  ASSERT_EQ(whole.exitCode, 0) << whole.output;
  ASSERT_EQ(sun.exitCode, 0) << sun.output;
  const auto jw = nlohmann::json::parse(whole.output), js = nlohmann::json::parse(sun.output);
  EXPECT_FALSE(jw.contains("lights"));
  const auto lights = lp::lightsFromJson(js, "coeffs --sun");
  ASSERT_EQ(lights.size(), 1u);
  EXPECT_GT(lights[0].share, 0.5f);  // the sun holds more than half the power
  const lp::Sh9 all = lp::coefficientsFromJson(jw, "coeffs"),
                sum = lp::coefficientsFromJson(js, "coeffs --sun") + lp::lightsToSh(lights);
  for (int k = 0; k < lp::kShCount; ++k)
    for (int ch = 0; ch < 3; ++ch)
      EXPECT_NEAR(sum.c[k][ch], all.c[k][ch], 1e-3 * all.c[0][ch]) << lp::kShNames[k];
  // --env-rotate turns the lights with the coefficients: yaw 90 about +z takes (x, y, z) to
  // (-y, x, z).
  const auto turned = lpt::runLiveprobe("coeffs " + map + " --sun --env-rotate 90,0,0");
  ASSERT_EQ(turned.exitCode, 0) << turned.output;
  const auto lt = lp::lightsFromJson(nlohmann::json::parse(turned.output), "turned");
  ASSERT_EQ(lt.size(), 1u);
  EXPECT_LT(glm::length(lt[0].dir - glm::vec3(-lights[0].dir.y, lights[0].dir.x, lights[0].dir.z)),
            1e-4f);
  // --coeffs reads the lights back: the render of a file with a light differs from without.
  lpt::TempDir tmp;
  const std::string f = tmp / "sun.json", g = tmp / "sky.json";
  std::ofstream(f) << sun.output;
  nlohmann::json sky = js;
  sky.erase("lights");
  std::ofstream(g) << sky.dump();
  EXPECT_EQ(lpt::runLiveprobe("render --coeffs " + f + " --exposure 1 --size 64x36 --out " +
                              (tmp / "a.png"))
                .exitCode,
            0);
  EXPECT_EQ(lpt::runLiveprobe("render --coeffs " + g + " --exposure 1 --size 64x36 --out " +
                              (tmp / "b.png"))
                .exitCode,
            0);
  std::ifstream a(tmp / "a.png", std::ios::binary), b(tmp / "b.png", std::ios::binary);
  const std::string pa((std::istreambuf_iterator<char>(a)), {}),
      pb((std::istreambuf_iterator<char>(b)), {});
  EXPECT_FALSE(pa.empty());
  EXPECT_NE(pa, pb);
  // A malformed light is a one-line error naming the file.
  nlohmann::json bad = js;
  bad["lights"][0]["direction"] = {0, 0, 0};
  std::ofstream(tmp / "bad.json") << bad.dump();
  lpt::expectOneLineError("render --coeffs " + (tmp / "bad.json") + " --out " + (tmp / "c.png"),
                          "bad.json", "direction");
}

// replay --sun --coeffs-out: every line holds the light, and it follows the synthetic sun (the
// generator's own direction) within 0.5 degrees, through the whole capture pipeline.
TEST(LightsCli, ReplayTracksTheSunIntoCoeffsOut) {
  lpt::TempDir tmp;
  const std::string out = tmp / "c.jsonl";
  const auto r = lpt::runLiveprobe(
      "replay synthetic:512x256@10 --frames 30 --headless --msaa 1 "
      "--size 64x36 --quiet --sun --coeffs-out " +
      out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("lights: in 30 of 30 frames"), std::string::npos) << r.output;
  std::ifstream in(out);
  int n = 0;
  for (std::string line; std::getline(in, line); ++n) {
    const auto j = nlohmann::json::parse(line);
    const auto lights = lp::lightsFromJson(j, "line");
    ASSERT_EQ(lights.size(), 1u) << line;
    const double t = j["time"].get<double>();
    EXPECT_LT(angleDeg(dvec3(lights[0].dir), dvec3(lp::syntheticSunDirection(t))), 0.5) << t;
  }
  EXPECT_EQ(n, 30);
}

// --smooth: a light's direction moves by slerp and its power by the coefficients' average.
TEST(Lights, SmoothingSlerpsTheDirection) {
  lp::LightSmoother smoother(1.0);
  lp::Light a, b;
  a.dir = {1, 0, 0}, a.power = glm::vec3(2.0f), a.angularRadius = 0.01f;
  b.dir = glm::vec3(std::cos(glm::radians(10.0f)), std::sin(glm::radians(10.0f)), 0),
  b.power = glm::vec3(4.0f), b.angularRadius = 0.01f;
  smoother.update({a}, 0.0);
  const auto s = smoother.update({b}, 0.5);  // alpha = 1 - exp(-0.5)
  const double alpha = 1 - std::exp(-0.5);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_NEAR(angleDeg(dvec3(s[0].dir), dvec3(a.dir)), 10.0 * alpha, 1e-3);
  EXPECT_NEAR(std::abs(glm::length(s[0].dir) - 1.0f), 0.0, 1e-6);
  EXPECT_NEAR(s[0].power.x, 2.0 + 2.0 * alpha, 1e-5);
  // A light more than 20 degrees from any before starts afresh; a jump back in time restarts.
  lp::Light c = a;
  c.dir = {-1, 0, 0};
  EXPECT_EQ(smoother.update({c}, 1.0)[0].dir, c.dir);
  EXPECT_EQ(smoother.update({a}, 0.2)[0].dir, a.dir);
}

}  // namespace

namespace {

// An equirect of six equal lamps (discs of 3 degrees) around the horizon, alternately 30 degrees
// above and below it, on a dim uniform sky; float RGB, R&H frame (+z up, the top row).
cv::Mat sixLampMap(int w, int h) {
  cv::Mat img(h, w, CV_32FC3, cv::Scalar::all(0.02));
  std::vector<dvec3> lamps;
  for (int i = 0; i < 6; ++i) {
    const double az = std::numbers::pi / 3 * i, el = glm::radians(i % 2 ? 30.0 : -30.0);
    lamps.push_back({std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)});
  }
  const double cosR = std::cos(glm::radians(3.0));
  for (int i = 0; i < h; ++i) {
    const double t = std::numbers::pi * (i + 0.5) / h;
    for (int j = 0; j < w; ++j) {
      const double p = 2 * std::numbers::pi * (j + 0.5) / w;
      const dvec3 d(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
      for (const dvec3& l : lamps)
        if (glm::dot(d, l) >= cosR) img.at<cv::Vec3f>(i, j) = cv::Vec3f(40, 40, 40);
    }
  }
  return img;
}

// The sum over an 8-bit sRGB image of its linear values (every channel).
double linearSum(const cv::Mat& srgb) {
  double s = 0;
  for (auto it = srgb.begin<cv::Vec3b>(); it != srgb.end<cv::Vec3b>(); ++it)
    for (int ch = 0; ch < 3; ++ch) {
      const double c = (*it)[ch] / 255.0;
      s += c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
    }
  return s;
}

}  // namespace

// Every light found is drawn: six equal lamps are six lights, and the light a render shows,
// summed over views from three sides at a fixed exposure with the linear tone map, is the same
// whether six, four or no lights leave the coefficients (what is not a light stays in them).
TEST(LightsCli, SixLampsAreAllDrawn) {
  lpt::TempDir tmp;
  const std::string map = tmp / "lamps.hdr";
  ASSERT_TRUE(cv::imwrite(map, sixLampMap(1024, 512)));
  const auto found = lpt::runLiveprobe("coeffs " + map + " --lights 6");
  ASSERT_EQ(found.exitCode, 0) << found.output;
  const auto lights = lp::lightsFromJson(nlohmann::json::parse(found.output), "coeffs");
  ASSERT_EQ(lights.size(), 6u);
  for (const lp::Light& l : lights)  // equal lamps, equal shares
    EXPECT_NEAR(l.share, lights[0].share, 0.02 * lights[0].share);

  auto renderedLight = [&](const std::string& lightsOption) {
    double sum = 0;
    for (int yaw : {0, 120, 240}) {
      const std::string out = tmp / ("view" + std::to_string(yaw) + ".png");
      const auto r = lpt::runLiveprobe("render --headless --env " + map + " " + lightsOption +
                                       " --no-background --tonemap linear --exposure 0.25" +
                                       " --msaa 1 --size 256x256 --yaw " + std::to_string(yaw) +
                                       " --out " + out);
      EXPECT_EQ(r.exitCode, 0) << r.output;
      const cv::Mat img = cv::imread(out);
      double hi;
      cv::minMaxLoc(img.reshape(1), nullptr, &hi);
      EXPECT_LT(hi, 255) << lightsOption << ": clipped, the sum would not be the light";
      sum += linearSum(img);
    }
    return sum;
  };
  const double six = renderedLight("--lights 6"), four = renderedLight("--lights 4"),
               none = renderedLight("");
  EXPECT_NEAR(six / four, 1.0, 0.03) << six << " against " << four;
  EXPECT_NEAR(six / none, 1.0, 0.03) << six << " against " << none;
}
