// A chrome ball found in the frame (--circle auto): frames of a map's mirror ball (reflectance
// 0.6, so the rim darkens against the scene behind it) in front of a view of the same map, the
// circle known; the found circle against it, and the coefficients through each.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "liveprobe/capture/ball.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/frame/srgb.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/projector.h"
#include "sh_compare.h"
#include "test_util.h"

namespace {

glm::vec3 mapAt(const lp::Image& map, glm::vec3 d) {
  const glm::vec2 at = *lp::layoutPixel(lp::Layout::Equirect, map.width, map.height, d);
  const int x = std::clamp(int(at.x), 0, map.width - 1),
            y = std::clamp(int(at.y), 0, map.height - 1);
  const float* p = map.pixel(x, y);
  return {p[0], p[1], p[2]};
}

/// A W x H float frame: the ball (circle cx, cy, r) reflecting `map` as the mirrorball layout
/// reads it, times 0.6; around it the scene behind the ball as a 40-degree view looking along +x.
lp::Frame ballFrame(const lp::Image& map, int w, int h, glm::vec3 circle) {
  lp::LayoutSpec spec(lp::Layout::MirrorBall);
  spec.circle = circle;
  lp::Frame f;
  f.width = w, f.height = h;
  f.format = lp::PanoramaFormat::RgbF32;
  f.rgb.assign(3 * std::size_t(w) * h, 0.0f);
  const double pixelAngle = glm::radians(40.0) / w;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      glm::vec3 sum(0.0f);
      for (const float a : {0.25f, 0.75f})
        for (const float b : {0.25f, 0.75f}) {
          const float u = (x + a - circle.x) / circle.z, v = (y + b - circle.y) / circle.z;
          const float rr = u * u + v * v;
          if (rr < 1.0f) {
            // The ball's normal (towards the camera at -x... seen from it: x right, y down), and
            // the direction it reflects: the layout's own formula, t = 2 asin(r).
            const float r = std::sqrt(rr), t = 2.0f * std::asin(r), p = std::atan2(-v, u);
            const glm::vec3 l(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
            sum += 0.6f * mapAt(map, lp::angularToWorld(l)) / 4.0f;
          } else {
            const glm::vec3 d =
                glm::normalize(glm::vec3(1.0f, -float((x + a - w / 2.0) * pixelAngle),
                                         -float((y + b - h / 2.0) * pixelAngle)));
            sum += mapAt(map, d) / 4.0f;
          }
        }
      std::copy(&sum[0], &sum[0] + 3, &f.rgb[3 * (std::size_t(y) * w + x)]);
    }
  return f;
}

lp::Sh9 through(const lp::Frame& f, glm::vec3 circle) {
  lp::LayoutSpec spec(lp::Layout::MirrorBall);
  spec.circle = circle;
  return lp::Projector(spec, f.width, f.height)
      .project(lp::PanoramaView::rgbF32(f.rgb.data(), f.width, f.height, spec));
}

TEST(Ball, FoundAsWellAsTheTrueCircle) {
  struct Case {
    const char* map;
    glm::vec3 circle;
  };
  for (const Case& c : {Case{"equirect/pedestrian_overpass_1k.hdr", {700.3f, 330.7f, 250.4f}},
                        Case{"equirect/quarry_01_1k.hdr", {512.6f, 401.2f, 181.7f}},
                        Case{"equirect/royal_esplanade_1k.hdr", {820.45f, 300.15f, 205.3f}}}) {
    const lp::Image map = lp::loadImage(lpt::dataPath(c.map));
    const glm::vec3 truth = c.circle;
    const lp::Frame f = ballFrame(map, 1280, 720, truth);
    const auto t0 = std::chrono::steady_clock::now();
    const auto found = lp::findBall(f);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_TRUE(found) << c.map;
    std::printf("%s: found %.3f %.3f %.3f off (rim rms %.3f px, %d sectors) in %.0f ms\n", c.map,
                found->x - truth.x, found->y - truth.y, found->radius - truth.z, found->rimResidual,
                found->rimSectors, ms);
    EXPECT_NEAR(found->x, truth.x, 0.3) << c.map;
    EXPECT_NEAR(found->y, truth.y, 0.3) << c.map;
    EXPECT_NEAR(found->radius, truth.z, 0.3) << c.map;
    const lp::Sh9 want = through(f, truth),
                  got =
                      through(f, glm::vec3(float(found->x), float(found->y), float(found->radius)));
    const double worst = lpt::worstOfL00(got, want);
    std::printf("%s: worst %.3f%% of L00\n", c.map, 100 * worst);
    EXPECT_LT(worst, 0.005) << c.map;
  }
}

}  // namespace

// A camera's 8-bit frame of the ball (exposed so the sky behind it is mid-grey, the sun clipped)
// is found as well; a frame with no ball in it (the map itself, a flat grey) gives none.
TEST(Ball, FoundInAnEightBitFrameAndNotWhereThereIsNone) {
  const lp::Image map = lp::loadImage(lpt::dataPath("equirect/pedestrian_overpass_1k.hdr"));
  const glm::vec3 truth{640.5f, 360.25f, 220.6f};
  const lp::Frame f = ballFrame(map, 1280, 720, truth);
  lp::Frame bytes;
  bytes.width = f.width, bytes.height = f.height;
  bytes.format = lp::PanoramaFormat::BgrU8;
  bytes.bgr8.resize(f.rgb.size());
  std::vector<float> sorted(f.rgb.begin(), f.rgb.end());
  std::nth_element(sorted.begin(), sorted.begin() + long(sorted.size() / 2), sorted.end());
  const float exposure = 0.18f / sorted[sorted.size() / 2];
  for (std::size_t i = 0; i < f.rgb.size(); i += 3)
    for (int c = 0; c < 3; ++c)
      bytes.bgr8[i + 2 - std::size_t(c)] = std::uint8_t(std::lround(
          255.0f * lp::linearToSrgb(std::clamp(f.rgb[i + std::size_t(c)] * exposure, 0.0f, 1.0f))));
  const auto found = lp::findBall(bytes);
  ASSERT_TRUE(found);
  std::printf("8-bit: found %.3f %.3f %.3f off (rim rms %.3f px)\n", found->x - truth.x,
              found->y - truth.y, found->radius - truth.z, found->rimResidual);
  const lp::Sh9 want = through(f, truth),
                got = through(f, glm::vec3(float(found->x), float(found->y), float(found->radius)));
  const double worst = lpt::worstOfL00(got, want);
  std::printf("8-bit: worst %.3f%% of L00\n", 100 * worst);
  EXPECT_LT(worst, 0.005);
  // scripts/lens-pictures: the frame as a camera's JPEG (recordings/ball/), and at half size with
  // the circle found drawn on it (docs/images/ball_found.png).
  if (const char* dir = std::getenv("LIVEPROBE_LENS_PICTURES")) {
    const cv::Mat frame(bytes.height, bytes.width, CV_8UC3, bytes.bgr8.data());
    cv::imwrite(std::string(dir) + "/ball.jpg", frame, {cv::IMWRITE_JPEG_QUALITY, 95});
    cv::Mat half;
    cv::resize(frame, half, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
    // (cv::circle's shift: coordinates in 1/16 pixel; OpenCV's pixel centres are whole numbers.)
    cv::circle(half,
               cv::Point(int(std::lround(16 * (0.5 * found->x - 0.5))),
                         int(std::lround(16 * (0.5 * found->y - 0.5)))),
               int(std::lround(16 * 0.5 * found->radius)), cv::Scalar(0, 0, 255), 1, cv::LINE_AA,
               4);
    cv::imwrite(std::string(dir) + "/ball_found.png", half);
  }

  lp::Frame plain;
  plain.width = map.width, plain.height = map.height;
  plain.format = lp::PanoramaFormat::RgbF32;
  plain.rgb = map.rgb;
  EXPECT_FALSE(lp::findBall(plain));
  lp::Frame grey = plain;
  std::fill(grey.rgb.begin(), grey.rgb.end(), 0.5f);
  EXPECT_FALSE(lp::findBall(grey));
}

// The command line: `coeffs --layout mirrorball --circle auto` says the circle it found and gives
// the true circle's coefficients within 0.5% of L00; no ball, and bench (which times one circle),
// are one line each.
TEST(Ball, CircleAutoFromTheCommandLine) {
  const lp::Image map = lp::loadImage(lpt::dataPath("equirect/quarry_01_1k.hdr"));
  const glm::vec3 truth{512.6f, 401.2f, 181.7f};
  const lp::Frame f = ballFrame(map, 1280, 720, truth);
  lpt::TempDir tmp;
  lp::Image image(f.width, f.height);
  image.rgb = f.rgb;
  const std::string file = tmp / "ball.exr";
  lp::saveImage(file, image);
  const auto r =
      lpt::runLiveprobe("coeffs " + file + " --layout mirrorball --circle auto --format json");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("mirror ball found: --circle 51"), std::string::npos) << r.output;
  const auto j = nlohmann::json::parse(r.output.substr(r.output.find('{')));
  lp::Sh9 cli;
  for (int k = 0; k < 9; ++k)
    for (int c = 0; c < 3; ++c)
      cli.c[k][c] = j["coefficients"][std::string(lp::kShNames[k])][c].get<float>();
  EXPECT_LT(lpt::worstOfL00(cli, through(f, truth)), 0.005) << r.output;

  const std::string flat = tmp / "flat.exr";
  lp::Image grey(320, 180);
  std::fill(grey.rgb.begin(), grey.rgb.end(), 0.5f);
  lp::saveImage(flat, grey);
  lpt::expectOneLineError("coeffs " + flat + " --layout mirrorball --circle auto", flat,
                          "found no mirror ball");
  lpt::expectOneLineError("bench " + file + " --layout mirrorball --circle auto --frames 1",
                          "--circle auto", "bench times one circle throughout");
  lpt::expectOneLineError("coeffs " + file + " --circle auto", "--circle", "mirrorball only");
}

// A stream (replay of an image sequence, --circle auto): no ball in the first frames (skipped, not
// counted), then the ball still, moving 2.5 px a frame, covered for two frames (said lost, the
// last circle kept at confidence 0, the last good lighting held), and uncovered where it moved
// to (found again). Each record's
// circle is the true one within 0.3 px, and its coefficients are those of the frame through the
// true circle within 0.5% of L00; the still frames keep one circle.
TEST(Ball, FollowedThroughAStream) {
  const lp::Image map = lp::loadImage(lpt::dataPath("equirect/quarry_01_1k.hdr"));
  constexpr int kW = 960, kH = 540;
  struct Shot {
    glm::vec3 circle;  ///< radius 0: no ball
    bool covered = false;
  };
  const glm::vec3 a{400.3f, 280.6f, 150.2f};
  std::vector<Shot> shots = {{{0, 0, 0}}, {{0, 0, 0}}, {a}, {a}, {a}};
  glm::vec3 c = a;
  for (int i = 0; i < 4; ++i) c += glm::vec3(2.5f, -1.0f, 0.3f), shots.push_back({c});
  shots.push_back({c, true}), shots.push_back({c, true});
  c += glm::vec3(1.5f, 0.5f, 0.0f);
  shots.push_back({c}), shots.push_back({c});
  lpt::TempDir tmp;
  std::vector<lp::Frame> frames;
  for (std::size_t i = 0; i < shots.size(); ++i) {
    const Shot& s = shots[i];
    // No ball: the scene alone (a circle far off the frame).
    lp::Frame f = ballFrame(map, kW, kH, s.circle.z > 0 ? s.circle : glm::vec3(-1e4f, -1e4f, 1));
    if (s.covered)  // a dark hand over the ball and around it
      for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
          if (std::hypot(x + 0.5f - s.circle.x, y + 0.5f - s.circle.y) < 1.3f * s.circle.z)
            std::fill_n(&f.rgb[3 * (std::size_t(y) * kW + x)], 3, 0.02f);
    lp::Image image(kW, kH);
    image.rgb = f.rgb;
    char name[32];
    std::snprintf(name, sizeof name, "f_%03zu.exr", i);
    lp::saveImage(tmp / name, image);
    frames.push_back(std::move(f));
  }
  const std::string out = tmp / "c.jsonl";
  const auto r = lpt::runLiveprobe(
      "replay " + lpt::shellQuote(tmp / "f_%03d.exr") +
      " --layout mirrorball --circle auto --headless --size 32x18 --coeffs-out " + out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("mirror ball found at frame 3: --circle 400."), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("mirror ball lost at frame 10: keeping --circle 410."), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("mirror ball found again at frame 12: --circle 411."), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("mirror ball (--circle auto): found after 2 frames"), std::string::npos)
      << r.output;
  std::ifstream lines(out);
  std::string line;
  std::size_t n = 0;
  std::optional<glm::vec3> stillCircle;
  lp::Sh9 lastGood;
  for (std::size_t i = 2; std::getline(lines, line); ++i, ++n) {
    ASSERT_LT(i, shots.size());
    SCOPED_TRACE("frame " + std::to_string(i + 1));
    const auto j = nlohmann::json::parse(line);
    const Shot& s = shots[i];
    ASSERT_TRUE(j.contains("ball")) << line;
    const glm::vec3 got(j["ball"]["circle"][0].get<float>(), j["ball"]["circle"][1].get<float>(),
                        j["ball"]["circle"][2].get<float>());
    EXPECT_EQ(j["ball"]["lost"].get<bool>(), s.covered);
    EXPECT_NEAR(got.x, s.circle.x, 0.3);
    EXPECT_NEAR(got.y, s.circle.y, 0.3);
    EXPECT_NEAR(got.z, s.circle.z, 0.3);
    if (i <= 4) {  // the still ball: one circle
      if (!stillCircle) stillCircle = got;
      EXPECT_EQ(got, *stillCircle);
    }
    lp::Sh9 rec;
    for (int k = 0; k < 9; ++k)
      for (int ch = 0; ch < 3; ++ch)
        rec.c[k][ch] = j["coefficients"][std::string(lp::kShNames[k])][ch].get<float>();
    EXPECT_EQ(j["confidence"]["held"].get<bool>(), s.covered);
    if (s.covered) {  // the last good lighting, held
      EXPECT_EQ(j["confidence"]["value"].get<double>(), 0.0);
      EXPECT_EQ(lpt::worstOfL00(rec, lastGood), 0.0);
      continue;
    }
    lastGood = rec;
    const double worst = lpt::worstOfL00(rec, through(frames[i], s.circle));
    std::printf("frame %zu: circle off %.3f %.3f %.3f, worst %.3f%% of L00\n", i + 1,
                got.x - s.circle.x, got.y - s.circle.y, got.z - s.circle.z, 100 * worst);
    EXPECT_LT(worst, 0.005);
  }
  EXPECT_EQ(n, shots.size() - 2);
}
