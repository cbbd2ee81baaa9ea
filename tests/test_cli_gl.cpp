// The drawing commands end to end: render (OSMesa), view in a real GLFW window under Xvfb, model
// textures, and bad input.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "liveprobe/backends.h"
#include "test_util.h"

namespace {

using lpt::expectOneLineError;
using lpt::lineCount;
using lpt::runLiveprobe;

// Spread of pixel values: a blank image has none.
double spread(const cv::Mat& img) {
  double lo, hi;
  cv::minMaxLoc(img.reshape(1), &lo, &hi);
  return hi - lo;
}

TEST(CliGl, RenderHeadlessWithEnvironment) {
  lpt::TempDir tmp;
  const std::string out = tmp / "bunny.png";
  const auto r = runLiveprobe(
      "render --headless --env " + lpt::dataPath("probes/latlong_256x128/grace.hdr") + " --model " +
      lpt::dataPath("models/stanford-bunny.obj") + " --size 320x240 --out " + out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("OSMesa"), std::string::npos) << r.output;
  const cv::Mat img = cv::imread(out);
  ASSERT_EQ(img.cols, 320);
  ASSERT_EQ(img.rows, 240);
  EXPECT_GT(spread(img), 100);
}

#if LIVEPROBE_WITH_GLFW
// The window path runs for real: GLFW on Xvfb (xvfb-run), screenshot not blank, and the same
// pixels as the OSMesa path (both are llvmpipe, drawing the same commands).
TEST(CliGl, ViewWindowUnderXvfb) {
  lpt::TempDir tmp;
  const std::string common =
      "--coeff L00=0.8 --coeff L10=0.3,0.1,0.0 --size 200x150 --frames 3 --no-hud ";
  const std::string win = tmp / "window.png", off = tmp / "offscreen.png";
  const std::string xvfb = lpt::xvfbRun("640x480x24");
  const auto run =
      lpt::runCommand(xvfb + LIVEPROBE_BIN + " view " + common + "--screenshot " + win);
  const std::string& out = run.output;
  ASSERT_EQ(run.exitCode, 0) << out;
  EXPECT_NE(out.find("GLFW window"), std::string::npos) << "did not use a window: " << out;
  const cv::Mat a = cv::imread(win);
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a.cols, 200);
  EXPECT_GT(spread(a), 100) << "blank screenshot";
  ASSERT_EQ(runLiveprobe("view --headless " + common + "--screenshot " + off).exitCode, 0);
  const cv::Mat b = cv::imread(off);
  ASSERT_EQ(a.size(), b.size());
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  double worst;
  cv::minMaxLoc(diff.reshape(1), nullptr, &worst);
  EXPECT_LE(worst, 2) << "window and offscreen renders differ";
}
#endif  // LIVEPROBE_WITH_GLFW

// An albedo texture from the model's material is multiplied in: a quad textured half red, half
// green under white light shows both colours.
TEST(CliGl, AlbedoTextureFromMaterial) {
  lpt::TempDir tmp;
  cv::Mat tex(64, 64, CV_8UC3, cv::Scalar(0, 0, 255));        // BGR: red
  tex(cv::Rect(32, 0, 32, 64)).setTo(cv::Scalar(0, 255, 0));  // right half green
  ASSERT_TRUE(cv::imwrite(tmp / "albedo.png", tex));
  std::ofstream(tmp / "quad.mtl") << "newmtl m\nKd 1 1 1\nmap_Kd albedo.png\n";
  std::ofstream(tmp / "quad.obj") << "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                                     "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl m\n"
                                     "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n";
  const std::string out = tmp / "quad.png";
  const auto r = runLiveprobe("render --headless --coeff L00=3 --model " + tmp / "quad.obj" +
                              " --size 200x200 --distance 3 --exposure 1 --out " + out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const cv::Mat img = cv::imread(out);
  const cv::Vec3b left = img.at<cv::Vec3b>(100, 80), right = img.at<cv::Vec3b>(100, 120);
  EXPECT_GT(left[2], 150);  // red
  EXPECT_LT(left[1], 30);
  EXPECT_GT(right[1], 150);  // green
  EXPECT_LT(right[2], 30);
}

TEST(CliGlBadInput, MissingModel) {
  expectOneLineError("render --headless --coeff L00=1 --model /nonexistent/bunny.obj",
                     "/nonexistent/bunny.obj", "no such file");
}

TEST(CliGlBadInput, CorruptModel) {
  lpt::TempDir tmp;
  const std::string f = tmp / "broken.ply";
  std::ofstream(f, std::ios::binary)
      << "ply\nformat binary_little_endian 1.0\nelement vertex 1000\n"
         "property float x\nend_header\n\x01\x02";
  expectOneLineError("render --headless --coeff L00=1 --model " + f, f, "model");
}

TEST(CliGlBadInput, ModelWithNoFaces) {
  lpt::TempDir tmp;
  const std::string f = tmp / "points.obj";
  std::ofstream(f) << "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  expectOneLineError("render --headless --coeff L00=1 --model " + f, f, "no triangles");
}

TEST(CliGlBadInput, UnknownCoefficientName) {
  expectOneLineError("render --headless --coeff L33=0.5", "L33", "unknown coefficient name");
  expectOneLineError("render --headless --coeff L20=abc", "L20", "not a number");
  expectOneLineError("render --headless", "render", "give the lighting");
}

TEST(CliGlBadInput, CorruptCoefficientFile) {
  lpt::TempDir tmp;
  const std::string f = tmp / "c.json";
  std::ofstream(f) << "{\"coefficients\": {\"L00\": [1, 2]}}";
  expectOneLineError("render --headless --coeffs " + f, f, "L00");
}

}  // namespace

namespace {

// render --coeffs reads what coeffs writes: the same lighting as render --env (no background).
TEST(CliGl, RenderFromCoefficientFileMatchesRenderFromEnvironment) {
  lpt::TempDir tmp;
  const std::string env = lpt::dataPath("probes/latlong_256x128/uffizi.hdr");
  const std::string json = tmp / "uffizi.json", a = tmp / "a.png", b = tmp / "b.png";
  auto r = lpt::runLiveprobe("coeffs " + env + " > " + json);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  r = lpt::runLiveprobe("render --headless --coeffs " + json +
                        " --size 160x120 --exposure 2 --out " + a);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  r = lpt::runLiveprobe("render --headless --env " + env +
                        " --no-background --size 160x120 --exposure 2 --out " + b);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const cv::Mat x = cv::imread(a), y = cv::imread(b);
  ASSERT_EQ(x.size(), y.size());
  cv::Mat diff;
  cv::absdiff(x, y, diff);
  double worst;
  cv::minMaxLoc(diff.reshape(1), nullptr, &worst);
  EXPECT_LE(worst, 1) << "JSON round trip changed the lighting";  // 9-digit floats: at most 1 LSB
  EXPECT_GT(spread(x), 50);
}

}  // namespace
