// The liveprobe program on files: output formats, and one-line errors on bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
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
  EXPECT_EQ(keys, (std::vector<std::string>{"source", "layout", "width", "height", "coverage",
                                            "coefficients"}));
  EXPECT_EQ(j["layout"], "equirect");
  EXPECT_EQ(j["coverage"], 1.0);
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

// GL 4.6, table 8.19: each cube face's direction from (sc, tc) in [-1, 1], where
// (s, t) = ((sc/|ma| + 1)/2, (tc/|ma| + 1)/2), and its cell in a horizontal cross; GL's face order.
struct GlFace {
  int col, row;
  glm::vec3 (*dir)(float sc, float tc);
};
constexpr GlFace kGlFaces[6] = {
    {2, 1, [](float sc, float tc) { return glm::vec3(1, -tc, -sc); }},   // +X
    {0, 1, [](float sc, float tc) { return glm::vec3(-1, -tc, sc); }},   // -X
    {1, 0, [](float sc, float tc) { return glm::vec3(sc, 1, tc); }},     // +Y
    {1, 2, [](float sc, float tc) { return glm::vec3(sc, -1, -tc); }},   // -Y
    {1, 1, [](float sc, float tc) { return glm::vec3(sc, -tc, 1); }},    // +Z
    {3, 1, [](float sc, float tc) { return glm::vec3(-sc, -tc, -1); }},  // -Z
};

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
  double worst = 0, scale = 0;
  for (const GlFace& f : kGlFaces)
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

/// Standard base64, as in a data URI.
std::vector<std::uint8_t> fromBase64(const std::string& s) {
  std::vector<std::uint8_t> out;
  std::uint32_t acc = 0;
  int bits = 0;
  for (char c : s) {
    const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const char* at = c ? std::strchr(k, c) : nullptr;
    if (!at) continue;  // padding
    acc = acc << 6 | std::uint32_t(at - k);
    if ((bits += 6) >= 8) out.push_back(std::uint8_t(acc >> (bits -= 8)));
  }
  return out;
}

/// Solid angle of the part of a cube face (at distance 1) from (0, 0) to (x, y).
double faceArea(double x, double y) { return std::atan2(x * y, std::sqrt(x * x + y * y + 1)); }

// The glTF export's specular cube, read as a glTF reader reads it (Babylon.js, the extension's
// reference reader: each PNG row flipped back, RGBD decoded as pow(rgb, 2.2) / alpha, times the
// light's intensity), projected onto the nine functions by each texel's exact solid angle:
// the coefficients the same document declares (irradianceCoefficients, Condon-Shortley signs,
// over A_l), within 2% of L00, on every map of the data.
TEST(Cli, GltfSpecularCubeHoldsTheDeclaredCoefficients) {
  const std::pair<const char*, const char*> maps[] = {
      {"equirect/blouberg_sunrise_2_1k.hdr", ""},
      {"equirect/moonless_golf_1k.hdr", ""},
      {"equirect/pedestrian_overpass_1k.hdr", ""},
      {"equirect/quarry_01_1k.hdr", ""},
      {"equirect/royal_esplanade_1k.hdr", ""},
      {"equirect/venice_sunset_1k.hdr", ""},
      {"probes/latlong_256x128/ennis.hdr", ""},
      {"probes/latlong_256x128/grace.hdr", ""},
      {"probes/latlong_256x128/pisa.hdr", ""},
      {"probes/latlong_256x128/uffizi.hdr", ""},
      {"probes/latlong_256x128/wells.hdr", ""},
      {"probes/latlong_full/grace_latlong.exr", ""},
      {"probes/beach_probe.hdr", " --layout angular"},
      {"cube/pisaHDR", " --layout cube"}};
  constexpr float kSign[lp::kShCount] = {1, -1, 1, -1, 1, -1, 1, -1, 1};
  for (const auto& [file, layout] : maps) {
    const auto r = runLiveprobe("coeffs " + lpt::dataPath(file) + layout + " --format gltf");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto doc = nlohmann::json::parse(r.output);
    const auto& light = doc["extensions"]["EXT_lights_image_based"]["lights"][0];
    const float intensity = light["intensity"];
    const int n = light["specularImageSize"];
    lp::Sh9 declared, cube;
    for (int k = 0; k < lp::kShCount; ++k)
      for (int ch = 0; ch < 3; ++ch)
        declared.c[k][ch] = kSign[k] * light["irradianceCoefficients"][k][ch].get<float>() *
                            intensity /
                            lp::shCosineLobe(k < 1   ? 0
                                             : k < 4 ? 1
                                                     : 2);
    for (int f = 0; f < 6; ++f) {
      const std::string uri = doc["images"][light["specularImages"][0][f].get<int>()]["uri"];
      const auto png = fromBase64(uri.substr(uri.find(',') + 1));
      const cv::Mat face = cv::imdecode(png, cv::IMREAD_UNCHANGED);  // BGRA
      ASSERT_EQ(face.type(), CV_8UC4) << file;
      ASSERT_EQ(face.rows, n);
      for (int i = 0; i < n; ++i)  // i: GL's row (t), stored as the image's row n - 1 - i
        for (int j = 0; j < n; ++j) {
          const cv::Vec4b p = face.at<cv::Vec4b>(n - 1 - i, j);
          const double x0 = 2.0 * j / n - 1, x1 = 2.0 * (j + 1) / n - 1;
          const double y0 = 2.0 * i / n - 1, y1 = 2.0 * (i + 1) / n - 1;
          const double omega =
              faceArea(x0, y0) - faceArea(x0, y1) - faceArea(x1, y0) + faceArea(x1, y1);
          const glm::vec3 g =
              glm::normalize(kGlFaces[f].dir(float(x0 + x1) / 2, float(y0 + y1) / 2));
          const auto y = lp::shBasis(g);
          for (int ch = 0; ch < 3; ++ch) {
            const double v = std::pow(p[2 - ch] / 255.0, 2.2) / (p[3] / 255.0) * intensity;
            for (int k = 0; k < lp::kShCount; ++k) cube.c[k][ch] += float(v * y[k] * omega);
          }
        }
    }
    double worst = 0;
    for (int k = 0; k < lp::kShCount; ++k)
      for (int ch = 0; ch < 3; ++ch)
        worst = std::max(worst,
                         double(std::abs(cube.c[k][ch] - declared.c[k][ch]) / declared.c[0][ch]));
    std::printf("%s: the cube's nine, worst %.2f%% of L00\n", file, 100 * worst);
    EXPECT_LT(worst, 0.02) << file;
  }
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
      {LIVEPROBE_WITH_NETWORK, "network streams, H.264 and HEVC cameras (FFmpeg)",
       "live rtsp://127.0.0.1:1/x", "rtsp://127.0.0.1:1/x", "LIVEPROBE_WITH_NETWORK"},
      {LIVEPROBE_WITH_NETWORK, "network streams, H.264 and HEVC cameras (FFmpeg)",
       "replay http://127.0.0.1:1/pano.mp4", "http://127.0.0.1:1/pano.mp4",
       "LIVEPROBE_WITH_NETWORK"},
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
                              " --size 32x16 --format json");
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
