// The liveprobe program on files: output formats, and one-line errors on bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <opencv2/imgcodecs.hpp>

#include "liveprobe/backends.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/exchange/coeffs_io.h"
#include "liveprobe/sh/sh.h"
#include "test_util.h"

namespace {

using lpt::expectOneLineError;
using lpt::lineCount;
using lpt::runLiveprobe;
namespace fs = std::filesystem;

void writeConstantHdr(const std::string& path, int w, int h, float c) {
  cv::Mat m(h, w, CV_32FC3, cv::Scalar(c, c, c));
  ASSERT_TRUE(cv::imwrite(path, m));
}

TEST(Cli, HelpForEveryCommand) {
  for (const char* cmd : {"coeffs", "irradiance", "compare"}) {
    const auto r = runLiveprobe(std::string(cmd) + " --help");
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_NE(r.output.find("Usage: liveprobe " + std::string(cmd)), std::string::npos);
  }
  EXPECT_EQ(runLiveprobe("--help").exitCode, 0);
  EXPECT_NE(runLiveprobe("frobnicate").exitCode, 0);
}

TEST(Cli, CoeffsJsonIsExactlyTheDocumentedShape) {
  lpt::TempDir tmp;
  const std::string f = tmp / "const.hdr";
  writeConstantHdr(f, 64, 32, 2.0f);
  const auto r = runLiveprobe("coeffs " + f);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto j = nlohmann::ordered_json::parse(r.output);
  std::vector<std::string> keys;
  for (auto& [k, v] : j.items()) keys.push_back(k);
  EXPECT_EQ(keys,
            (std::vector<std::string>{"source", "layout", "width", "height", "coefficients"}));
  EXPECT_EQ(j["layout"], "equirect");
  EXPECT_EQ(j["width"], 64);
  std::vector<std::string> names;
  for (auto& [k, v] : j["coefficients"].items()) names.push_back(k);
  EXPECT_EQ(names, (std::vector<std::string>{"L00", "L1-1", "L10", "L11", "L2-2", "L2-1", "L20",
                                             "L21", "L22"}));
  // Radiance 2 everywhere (exact in RGBE): L00 = 4 pi 0.282095 * 2.
  EXPECT_NEAR(j["coefficients"]["L00"][1].get<double>(), 4 * std::numbers::pi * 0.282095 * 2, 1e-4);
  EXPECT_NEAR(j["coefficients"]["L20"][1].get<double>(), 0.0, 1e-4);
}

TEST(Cli, CoeffsTextAndGlsl) {
  lpt::TempDir tmp;
  const std::string f = tmp / "const.hdr";
  writeConstantHdr(f, 64, 32, 1.0f);
  const auto t = runLiveprobe("coeffs " + f + " --format text");
  EXPECT_EQ(t.exitCode, 0);
  EXPECT_NE(t.output.find("L2-2"), std::string::npos);
  const auto g = runLiveprobe("coeffs " + f + " --format glsl");
  EXPECT_EQ(g.exitCode, 0);
  std::size_t n = 0;
  for (std::size_t p = 0; (p = g.output.find("const mat4", p)) != std::string::npos; ++p) ++n;
  EXPECT_EQ(n, 3u);
  expectOneLineError("coeffs " + f + " --format yaml", "--format yaml", "expected json");
  expectOneLineError("coeffs " + f + " --window 1.5", "--window 1.5", "greater than 2");
}

// Irradiance of a constant environment c is pi c everywhere, by both methods; the file is
// written atomically (no temporary left beside it).
TEST(Cli, IrradianceMapOfConstantEnvironment) {
  lpt::TempDir tmp;
  const std::string f = tmp / "const.hdr";
  writeConstantHdr(f, 128, 64, 0.5f);
  for (const char* method : {"sh", "brute"}) {
    const std::string out = tmp / (std::string("e_") + method + ".exr");
    const auto r =
        runLiveprobe("irradiance " + f + " --out " + out + " --size 32x16 --method " + method);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const lp::Image e = lp::loadImage(out);
    ASSERT_EQ(e.width, 32);
    ASSERT_EQ(e.height, 16);
    for (float v : e.rgb) ASSERT_NEAR(v, std::numbers::pi * 0.5, 1e-3) << method;
  }
  int files = 0;
  for (auto& entry : fs::directory_iterator(tmp.path)) files += entry.is_regular_file();
  EXPECT_EQ(files, 3);
  expectOneLineError("irradiance " + f + " --out " + tmp / "nodir/x.hdr", "nodir",
                     "does not exist");
  expectOneLineError("irradiance " + f, "irradiance", "--out");
}

// irradiance --cube: each face texel holds E at the direction the OpenGL specification gives that
// texel (its cube-map table, restated here), turned into the world frame by liveprobe's GL map
// (GL (X, Y, Z) = (-y, z, x)); and the cross, read back as a cube layout, projects to the
// irradiance coefficients A_l L_lm (E is band-limited to l <= 2, so that is exact up to
// sampling).
TEST(Cli, IrradianceCubeFollowsOpenGlsFaceTable) {
  lpt::TempDir tmp;
  const std::string map = lpt::dataPath("probes/latlong_256x128/grace.hdr");
  const int n = 32;
  const std::string out = tmp / "cube.exr";
  auto r = runLiveprobe("irradiance " + map + " --cube " + std::to_string(n) + " --out " + out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  r = runLiveprobe("coeffs " + map);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const lp::Sh9 L = lp::coefficientsFromJson(nlohmann::json::parse(r.output), "coeffs");
  const lp::Image e = lp::loadImage(out);
  ASSERT_EQ(e.width, 4 * n);
  ASSERT_EQ(e.height, 3 * n);
  // GL 4.6, table 8.19: major axis, sc, tc for each face; (s, t) = ((sc/|ma| + 1)/2, ...).
  struct Face {
    int col, row;  // cell of the horizontal cross
    glm::vec3 (*dir)(float sc, float tc);
  };
  const Face faces[6] = {
      {2, 1, [](float sc, float tc) { return glm::vec3(1, -tc, -sc); }},   // +X
      {0, 1, [](float sc, float tc) { return glm::vec3(-1, -tc, sc); }},   // -X
      {1, 0, [](float sc, float tc) { return glm::vec3(sc, 1, tc); }},     // +Y
      {1, 2, [](float sc, float tc) { return glm::vec3(sc, -1, -tc); }},   // -Y
      {1, 1, [](float sc, float tc) { return glm::vec3(sc, -tc, 1); }},    // +Z
      {3, 1, [](float sc, float tc) { return glm::vec3(-sc, -tc, -1); }},  // -Z
  };
  double worst = 0, scale = 0;
  for (const Face& f : faces)
    for (int i = 0; i < n; i += 5)
      for (int j = 0; j < n; j += 5) {
        const float sc = 2 * (j + 0.5f) / n - 1, tc = 2 * (i + 0.5f) / n - 1;
        const glm::vec3 g = glm::normalize(f.dir(sc, tc));
        const glm::vec3 world(g.z, -g.x, g.y);
        const lp::Rgb truth = lp::evalIrradiance(L, world);
        const float* px = &e.rgb[(std::size_t(f.row * n + i) * e.width + f.col * n + j) * 3];
        for (int ch = 0; ch < 3; ++ch) {
          worst = std::max(worst, double(std::abs(px[ch] - truth[ch])));
          scale = std::max(scale, double(std::abs(truth[ch])));
        }
      }
  EXPECT_LT(worst / scale, 1e-5);
  r = runLiveprobe("coeffs " + out + " --layout cube");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const lp::Sh9 E = lp::coefficientsFromJson(nlohmann::json::parse(r.output), "cube");
  const lp::Sh9 truth = lp::toIrradiance(L);
  for (int k = 0; k < lp::kShCount; ++k)
    EXPECT_NEAR(E.c[k].x, truth.c[k].x, 2e-3 * truth.c[0].x) << lp::kShNames[k];
  expectOneLineError("irradiance " + map + " --cube 16 --size 64x32 --out " + out, "--cube",
                     "not both");
}

TEST(CliBadInput, EngineFormats) {
  const std::string map = lpt::dataPath("probes/latlong_256x128/grace.hdr");
  expectOneLineError("coeffs " + map + " --format povray", "--format povray", "expected json");
  expectOneLineError("replay synthetic:64x32 --headless --frames 1 --coeffs-format gltf",
                     "--coeffs-format gltf", "one JSON line");
  if (LIVEPROBE_WITH_MQTT) {
    expectOneLineError("replay synthetic:64x32 --headless --frames 1 --publish http://x/y",
                       "--publish http://x/y", "mqtt://");
    expectOneLineError("replay synthetic:64x32 --headless --frames 1 --publish mqtt://x",
                       "--publish mqtt://x", "no topic");
  }
  if (LIVEPROBE_WITH_STREAM)
    expectOneLineError("replay synthetic:64x32 --headless --frames 1 --serve 70000",
                       "--serve 70000", "0..65535");
  expectOneLineError("replay synthetic:64x32 --headless --frames 1 --serve-clients 4",
                     "--serve-clients", "go with --serve");
}

// The optional backends: --version lists the ones built in, and each one missing from the build
// is one line naming what asked for it and the CMake option that builds it, exit 1.
TEST(Backends, VersionListsThemAndAMissingOneIsOneLine) {
  const auto v = runLiveprobe("--version");
  ASSERT_EQ(v.exitCode, 0) << v.output;
  const std::string line = v.output.substr(v.output.find("backends: "));
  struct Case {
    bool built;           // in this build (liveprobe/backends.h)
    const char* label;    // in --version
    const char* command;  // what needs it
    const char* names;    // the one line names it
    const char* option;   // and the CMake option
  };
  const Case cases[] = {
      {LIVEPROBE_WITH_GLFW, "window (GLFW)", "view --coeff L00=1", "view", "LIVEPROBE_WITH_GLFW"},
      {LIVEPROBE_WITH_V4L2, "V4L2 cameras", "live /dev/video0", "live", "LIVEPROBE_WITH_V4L2"},
      {LIVEPROBE_WITH_STREAM, "WebSocket stream",
       "replay synthetic:64x32 --headless --frames 1 --serve 0", "--serve",
       "LIVEPROBE_WITH_STREAM"},
      {LIVEPROBE_WITH_MQTT, "MQTT",
       "replay synthetic:64x32 --headless --frames 1 --publish mqtt://127.0.0.1:1/t", "--publish",
       "LIVEPROBE_WITH_MQTT"},
  };
  const std::size_t without = line.find("built without");
  for (const Case& c : cases) {
    const std::size_t at = line.find(c.label);
    ASSERT_NE(at, std::string::npos) << line;
    if (c.built) {
      EXPECT_TRUE(without == std::string::npos || at < without) << c.label << ": " << line;
    } else {
      EXPECT_TRUE(without != std::string::npos && at > without) << c.label << ": " << line;
      expectOneLineError(c.command, c.names, std::string("built without"));
      expectOneLineError(c.command, c.names, c.option);
    }
  }
}

TEST(Cli, CompareJson) {
  const auto r = runLiveprobe("compare " + lpt::dataPath("probes/latlong_256x128/grace.hdr") +
                              " --size 32x16 --json");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  for (const char* k : {"mean_frac_total", "max_frac_total", "mean_rel_mean", "max_rel_mean",
                        "min_sh_over_mean", "sh_ms", "brute_ms"})
    EXPECT_TRUE(j.contains(k)) << k;
  // Mean irradiance is a quarter of the total intensity, so rel_mean = 4 frac_total.
  EXPECT_NEAR(j["mean_rel_mean"].get<double>(), 4 * j["mean_frac_total"].get<double>(), 1e-3);
  EXPECT_LT(j["mean_frac_total"].get<double>(), 0.05);
}

TEST(Cli, CompareFigure) {
  lpt::TempDir tmp;
  const std::string out = tmp / "err.png";
  const auto r = runLiveprobe("compare " + lpt::dataPath("probes/latlong_256x128/grace.hdr") +
                              " --size 32x16 --out " + out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const cv::Mat fig = cv::imread(out);
  ASSERT_FALSE(fig.empty());
  EXPECT_GT(fig.cols, 3 * 32);
  double lo, hi;
  cv::minMaxLoc(fig.reshape(1), &lo, &hi);
  EXPECT_GT(hi - lo, 100);  // not blank
}

// ---- Bad input ----------------------------------------------------------------------------

TEST(CliBadInput, MissingFile) {
  expectOneLineError("coeffs /nonexistent/env.hdr", "/nonexistent/env.hdr", "no such file");
}

TEST(CliBadInput, NotAnImage) {
  lpt::TempDir tmp;
  const std::string f = tmp / "notes.hdr";
  std::ofstream(f) << "this is not a picture\n";
  expectOneLineError("coeffs " + f, f, "not a readable image");
  const std::string g = tmp / "garbage.png";
  std::ofstream(g, std::ios::binary) << std::string("\x89PNG\r\n\x1a\n garbage garbage", 24);
  expectOneLineError("compare " + g, g, "image");
}

TEST(CliBadInput, TruncatedRadianceFile) {
  lpt::TempDir tmp;
  const std::string src = lpt::dataPath("equirect/royal_esplanade_1k.hdr");
  std::ifstream in(src, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const std::string f = tmp / "truncated.hdr";
  std::ofstream(f, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  expectOneLineError("coeffs " + f, f, "truncated");
}

TEST(CliBadInput, NanAndInfPixels) {
  lpt::TempDir tmp;
  cv::Mat m(32, 64, CV_32FC3, cv::Scalar(1, 1, 1));
  m.at<cv::Vec3f>(5, 7)[1] = NAN;
  m.at<cv::Vec3f>(9, 2)[0] = INFINITY;
  const std::string f = tmp / "nan.exr";
  ASSERT_TRUE(cv::imwrite(f, m));
  expectOneLineError("coeffs " + f, f, "NaN or Inf");
}

TEST(CliBadInput, AngularMapNotSquare) {
  lpt::TempDir tmp;
  const std::string f = tmp / "wide.hdr";
  writeConstantHdr(f, 64, 32, 1.0f);
  expectOneLineError("coeffs " + f + " --layout angular", f, "must be square");
}

TEST(CliBadInput, BadOptions) {
  expectOneLineError("coeffs a.hdr --layout spherical", "spherical", "unknown layout");
  expectOneLineError("compare a.hdr --size 64by32", "64by32", "size");
  expectOneLineError("coeffs a.hdr --bogus", "--bogus", "unknown option");
  expectOneLineError("coeffs", "coeffs", "missing argument");
}

}  // namespace
