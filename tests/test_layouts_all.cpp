// Every layout agrees: the same environment, resampled here into each layout by this test's own
// code (from the documented conventions), projects to the same coefficients as the equirect.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "layout_dirs.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/capture/open_source.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/projector.h"
#include "test_util.h"

namespace {

constexpr double kPi = std::numbers::pi;
using glm::dvec3;

// Bilinear lookup of the equirect at a world direction (the test's own inverse mapping).
dvec3 sampleEquirect(const lp::Image& eq, dvec3 d) {
  double p = std::atan2(d.y, d.x);
  if (p < 0) p += 2 * kPi;
  const double x = p / (2 * kPi) * eq.width - 0.5,
               y = std::acos(std::clamp(d.z, -1.0, 1.0)) / kPi * eq.height - 0.5;
  const int x0 = int(std::floor(x)), y0 = std::clamp(int(std::floor(y)), 0, eq.height - 1);
  const int y1 = std::min(y0 + 1, eq.height - 1);
  const double ax = x - std::floor(x), ay = std::clamp(y - y0, 0.0, 1.0);
  auto px = [&](int xx, int yy) {
    xx = ((xx % eq.width) + eq.width) % eq.width;
    const float* v = eq.pixel(xx, yy);
    return dvec3(v[0], v[1], v[2]);
  };
  return (1 - ay) * ((1 - ax) * px(x0, y0) + ax * px(x0 + 1, y0)) +
         ay * ((1 - ax) * px(x0, y1) + ax * px(x0 + 1, y1));
}

// Fills a W x H image by asking `dirAt(x, y)` (pixel centre) for each pixel's world direction;
// 4x4 supersampling within each pixel keeps the resampling from aliasing.
lp::Image resample(const lp::Image& eq, int w, int h, const lpt::DirAt& dirAt) {
  lp::Image out(w, h);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) {
      dvec3 sum(0);
      int n = 0;
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
          if (auto d = dirAt(j + (b + 0.5) / 4, i + (a + 0.5) / 4))
            sum += sampleEquirect(eq, *d), ++n;
      if (n) {
        sum /= double(n);
        float* p = out.pixel(j, i);
        p[0] = float(sum.x), p[1] = float(sum.y), p[2] = float(sum.z);
      }
    }
  return out;
}

lp::Sh9 project(const lp::Image& img, const lp::LayoutSpec& spec) {
  return lp::project(lp::PanoramaView::rgbF32(img.rgb.data(), img.width, img.height, spec));
}

std::array<double, 3> bandNorms(const lp::Sh9& L, int ch) {
  std::array<double, 3> n{};
  for (int k = 0; k < 9; ++k) n[lp::shBand(k)] += double(L.c[k][ch]) * L.c[k][ch];
  for (auto& v : n) v = std::sqrt(v);
  return n;
}

void expectSameLighting(const lp::Sh9& ref, const lp::Sh9& got, const std::string& what) {
  for (int ch = 0; ch < 3; ++ch) {
    for (int k = 0; k < 9; ++k)
      EXPECT_NEAR(got.c[k][ch], ref.c[k][ch], 0.01 * ref.c[0][ch])
          << what << " " << lp::kShNames[k] << " ch " << ch;
    const auto a = bandNorms(ref, ch), b = bandNorms(got, ch);
    for (int l = 0; l < 3; ++l)
      EXPECT_NEAR(b[l], a[l], 0.01 * a[l]) << what << " band " << l << " ch " << ch;
  }
}

class EveryLayout : public ::testing::Test {
 protected:
  void SetUp() override {
    eq_ = lp::loadImage(lpt::dataPath("equirect/royal_esplanade_1k.hdr"));
    ref_ = project(eq_, lp::Layout::Equirect);
  }
  lp::Image eq_;
  lp::Sh9 ref_;
};

TEST_F(EveryLayout, Angular) {
  auto img = resample(eq_, 512, 512, lpt::angularDirs(512));
  expectSameLighting(ref_, project(img, lp::Layout::Angular), "angular");
}

TEST_F(EveryLayout, MirrorBall) {
  // A 640x480 photo with the ball off-centre.
  const double cx = 300, cy = 250, R = 220;
  auto img = resample(eq_, 640, 480, lpt::mirrorBallDirs(cx, cy, R));
  lp::LayoutSpec spec(lp::Layout::MirrorBall);
  spec.circle = {float(cx), float(cy), float(R)};
  expectSameLighting(ref_, project(img, spec), "mirror ball");
}

TEST_F(EveryLayout, CubeCrosses) {
  const int n = 128;
  auto h = resample(eq_, 4 * n, 3 * n, lpt::cubeCrossDirs(n, false));
  expectSameLighting(ref_, project(h, lp::Layout::Cube), "horizontal cross");
  auto v = resample(eq_, 3 * n, 4 * n, lpt::cubeCrossDirs(n, true));
  expectSameLighting(ref_, project(v, lp::Layout::Cube), "vertical cross");
}

TEST_F(EveryLayout, DualFisheye) {
  for (float fov : {190.0f, 220.0f}) {
    const int h = 384, w = 2 * h;
    auto img = resample(eq_, w, h, lpt::dualFisheyeDirs(w, h, fov));
    lp::LayoutSpec spec(lp::Layout::DualFisheye);
    spec.fisheyeFovDeg = fov;
    expectSameLighting(ref_, project(img, spec), "dual fisheye " + std::to_string(int(fov)));
  }
}

// The cube-face source: Pisa's six real faces against the same courtyard's lat-long probe. Both
// are real data; their exposures and resolutions differ, so compare normalised band norms
// (rotation invariant) loosely: this guards the face assembly, not the resampling.
TEST(CubeFaces, PisaFacesMatchPisaLatlong) {
  const lp::Image lat = lp::loadImage(lpt::dataPath("probes/latlong_256x128/pisa.hdr"));
  const lp::Sh9 a = project(lat, lp::Layout::Equirect);
  auto src = lp::openSource(lpt::dataPath("cube/pisaHDR"));
  lp::Frame f;
  ASSERT_TRUE(src->next(f));
  ASSERT_EQ(f.width, 4 * 256);
  ASSERT_EQ(f.height, 3 * 256);
  lp::Image cross(f.width, f.height);
  cross.rgb = f.rgb;
  const lp::Sh9 b = project(cross, lp::Layout::Cube);
  for (int ch = 0; ch < 3; ++ch) {
    const auto na = bandNorms(a, ch), nb = bandNorms(b, ch);
    for (int l = 1; l < 3; ++l)
      EXPECT_NEAR(nb[l] / nb[0], na[l] / na[0], 0.1 * na[l] / na[0])
          << "band " << l << " ch " << ch;
  }
}

TEST(Layouts, RejectFramesThatDoNotFit) {
  EXPECT_NE(lp::layoutMismatch(lp::Layout::Cube, 1000, 500).find("4:3"), std::string::npos);
  EXPECT_NE(lp::layoutMismatch(lp::Layout::DualFisheye, 1000, 1000).find("2:1"), std::string::npos);
  EXPECT_NE(lp::layoutMismatch(lp::Layout::MirrorBall, 640, 480).find("circle"), std::string::npos);
  lp::LayoutSpec ball(lp::Layout::MirrorBall);
  ball.circle = {600, 240, 200};
  EXPECT_NE(lp::layoutMismatch(ball, 640, 480).find("does not fit"), std::string::npos);
}

// Solid angles of every layout sum to 4 pi; and layoutPixel inverts the sample directions.
TEST(Layouts, SolidAnglesAndInverse) {
  lp::LayoutSpec ball(lp::Layout::MirrorBall);
  ball.circle = {160, 120, 100};
  const std::vector<std::tuple<lp::LayoutSpec, int, int>> cases = {
      {lp::Layout::Equirect, 256, 128},
      {lp::Layout::Angular, 256, 256},
      {ball, 320, 240},
      {lp::Layout::Cube, 256, 192},
      {lp::Layout::Cube, 192, 256},
      {lp::Layout::DualFisheye, 512, 256}};
  for (const auto& [spec, w, h] : cases) {
    const auto s = lp::layoutSamples(spec, w, h);
    double total = 0;
    for (const auto& x : s) total += x.solidAngle;
    EXPECT_NEAR(total, 4 * kPi, 1e-3) << lp::layoutName(spec.layout) << " " << w << "x" << h;
    int checked = 0;
    for (int i = 0; i < h; i += 7)
      for (int j = 0; j < w; j += 5) {
        const auto& x = s[std::size_t(i) * w + j];
        if (x.solidAngle == 0) continue;
        const auto px = lp::layoutPixel(spec, w, h, x.dir);
        ASSERT_TRUE(px.has_value());
        // Inside the layout the inverse lands in the same pixel (dual-fisheye overlap pixels may
        // map to the other lens, which sees the same direction).
        if (spec.layout == lp::Layout::DualFisheye && std::abs(x.dir.x) < 0.3f) continue;
        EXPECT_NEAR(px->x, j + 0.5f, 0.51f) << lp::layoutName(spec.layout);
        EXPECT_NEAR(px->y, i + 0.5f, 0.51f) << lp::layoutName(spec.layout);
        ++checked;
      }
    EXPECT_GT(checked, 50);
  }
}

// The one frame path: a map of each layout, made here, gives the same coefficients, to the last
// digit, through a still command (coeffs), the capture pipeline (replay, one thread: the sums in
// the same order) and the accuracy evaluation (compare).
TEST_F(EveryLayout, TheSameCoefficientsThroughEveryCommand) {
  lpt::TempDir tmp;
  struct Case {
    std::string name, args;
    lp::Image image;
  };
  const int n = 32;
  const std::vector<Case> cases = {
      {"equirect", "", resample(eq_, 128, 64, lpt::equirectDirs(128, 64))},
      {"angular", "--layout angular", resample(eq_, 96, 96, lpt::angularDirs(96))},
      {"mirrorball", "--layout mirrorball --circle 70,60,50",
       resample(eq_, 160, 120, lpt::mirrorBallDirs(70, 60, 50))},
      {"cube", "--layout cube", resample(eq_, 4 * n, 3 * n, lpt::cubeCrossDirs(n, false))},
      {"fisheye", "--layout fisheye --fov 200",
       resample(eq_, 192, 96, lpt::dualFisheyeDirs(192, 96, 200))}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string file = tmp / (c.name + ".exr");
    lp::saveImage(file, c.image);
    const auto still = lpt::runLiveprobe("coeffs " + file + " " + c.args);
    ASSERT_EQ(still.exitCode, 0) << still.output;
    const auto replay = lpt::runLiveprobe(
        "replay " + file + " " + c.args +
        " --headless --frames 1 --threads 1 --size 32x18 --quiet --coeffs-out " + tmp / "c.jsonl");
    ASSERT_EQ(replay.exitCode, 0) << replay.output;
    const auto compare =
        lpt::runLiveprobe("compare " + file + " " + c.args + " --size 8x4 --format json");
    ASSERT_EQ(compare.exitCode, 0) << compare.output;
    const auto want = nlohmann::json::parse(still.output)["coefficients"];
    std::ifstream lines(tmp / "c.jsonl");
    std::string first;
    ASSERT_TRUE(std::getline(lines, first));
    const auto record = nlohmann::json::parse(first);
    EXPECT_EQ(record["coefficients"], want);
    EXPECT_EQ(nlohmann::json::parse(compare.output)["coefficients"], want);
    // The display's equirect is made on the capture thread, as its own stage, for exactly the
    // layouts GL does not draw as they are.
    const bool drawnAsIs = c.name == "equirect" || c.name == "angular";
    EXPECT_EQ(record["timings_ms"].contains("resample"), !drawnAsIs) << record["timings_ms"];
    if (!drawnAsIs) {
      EXPECT_GT(record["timings_ms"]["resample"].get<double>(), 0.0);
    }
  }
}

}  // namespace
