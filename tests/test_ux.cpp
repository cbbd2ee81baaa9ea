// What a person running liveprobe sees: the HUD (headless and in a real window under Xvfb, driven
// by xdotool), keys, orientation of lighting and background together, visible single-coefficient
// figures, clean stops on SIGINT, progress, the command line's refusals, and bench's report.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <regex>
#include <set>
#include <tuple>

#include "commands.h"
#include "dynamic_resolution.h"
#include "environment.h"
#include "hud.h"
#include "liveprobe/backends.h"
#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/open_source.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/gl/mesh.h"
#include "liveprobe/gl/renderer.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/sh.h"
#include "stream_sinks.h"
#include "test_util.h"

namespace {

// Shell: waits until process $pid catches SIGINT (bit 2 of SigCgt in /proc/PID/status); a signal
// sent before, while the dynamic loader still runs, would end it without its summary.
const std::string kAwaitSigintHandler =
    "for i in $(seq 2000); do m=$(awk '/^SigCgt/{print $2}' /proc/$pid/status 2>/dev/null); "
    "[ -n \"$m\" ] && (( 16#$m & 2 )) && break; done; ";

namespace fs = std::filesystem;
using lpt::expectOneLineError;
using lpt::runLiveprobe;

/// Runs a bash script line (the liveprobe binary is $LP), capturing stdout and stderr.
lpt::RunResult runShell(const std::string& script) {
  return lpt::runCommand("LP=" + lpt::shellQuote(LIVEPROBE_BIN) + " bash -c " +
                         lpt::shellQuote(script));
}

double meanAbsDiff(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::absdiff(a, b, d);
  const cv::Scalar m = cv::mean(d);
  return (m[0] + m[1] + m[2]) / 3;
}

// ---- the HUD, headless ------------------------------------------------------------------------

// The HUD's left panel sits at the top left and the light panel at the top right, drawn into
// the frames of render and replay with --hud and not without.
TEST(Hud, HeadlessHudIsDrawnAndNoHudIsNot) {
  lpt::TempDir tmp;
  const std::string common = "--headless --msaa 1 --size 1280x720 --env " +
                             lpt::dataPath("probes/latlong_256x128/uffizi.hdr") + " --out ";
  ASSERT_EQ(runLiveprobe("render " + common + tmp / "plain.png").exitCode, 0);
  const auto r = runLiveprobe("render --hud " + common + tmp / "hud.png");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const cv::Mat plain = cv::imread(tmp / "plain.png"), hud = cv::imread(tmp / "hud.png");
  ASSERT_FALSE(plain.empty());
  ASSERT_EQ(plain.size(), hud.size());
  const cv::Rect left(12, 12, 300, 200), right(1000, 12, 260, 300);
  EXPECT_GT(meanAbsDiff(plain(left), hud(left)), 10) << "no HUD status panel";
  EXPECT_GT(meanAbsDiff(plain(right), hud(right)), 10) << "no HUD light panel";

  // replay: --hud draws it into the written frames, --no-hud (the headless default) does not.
  const std::string src =
      "synthetic:128x64@30 --frames 3 --headless --msaa 1 --size 1280x720 --quiet --out-dir ";
  ASSERT_EQ(runLiveprobe("replay " + src + tmp / "a --hud").exitCode, 0);
  ASSERT_EQ(runLiveprobe("replay " + src + tmp / "b --no-hud").exitCode, 0);
  const cv::Mat a = cv::imread(tmp / "a/frame_000002.png"),
                b = cv::imread(tmp / "b/frame_000002.png");
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  EXPECT_GT(meanAbsDiff(a(left), b(left)), 10);
}

// At every size, the HUD leaves the model alone: the model is drawn on black, framed beside the
// panels, then the HUD over it; every pixel of the model is the same after the HUD as before.
// Each panel's content fits in the panel and the panel in the frame, and a headless frame has
// none of the window's controls (the background checkbox's check mark, Dear ImGui's
// CheckMark blue, is nowhere in the status panel).
TEST(Hud, NeverCoversTheModelAtAnySize) {
  const std::vector<glm::ivec2> sizes = {{320, 180},   {480, 270},  {640, 360},
                                         {960, 540},   {1280, 720}, {1920, 1080},
                                         {3840, 2160}, {600, 800},  {512, 512}};
  for (const glm::ivec2 fb : sizes) {
    SCOPED_TRACE(std::to_string(fb.x) + "x" + std::to_string(fb.y));
    auto ctx = lp::gl::createGlContext({lp::gl::Backend::Headless, fb.x, fb.y, "hud", false});
    lp::gl::Renderer renderer;
    renderer.setMesh(lp::makeUvSphere());
    lp::Sh9 L;
    L.c[0] = glm::vec3(2.0f);
    L.c[2] = glm::vec3(1.0f);
    const lp::Light sun{glm::normalize(glm::vec3(0.3f, 0.2f, 0.9f)), glm::radians(0.5f),
                        glm::vec3(1.0f), 0.4f, false};
    renderer.setLighting(L, {sun});
    lp::cli::Hud hud(*ctx);
    hud.setSource("synthetic:256x128@30", "equirect", true);
    for (int i = 0; i < 40; ++i) {
      lp::cli::HudSample h;
      h.frame = std::uint64_t(i);
      h.times[lp::Stage::Grab] = 1 + i % 3, h.times[lp::Stage::Project] = 0.2;
      h.times[lp::Stage::Render] = 12 + i % 5, h.latencyMs = 30;
      h.radiance = h.unsmoothed = L;
      h.unsmoothed.c[0] *= 1.0f + 0.01f * float(i % 4);
      h.lights = {sun};
      hud.push(h);
    }
    hud.setCounters({40, 40, 0, 0, 0.0, {"stream: 2 clients, 0 dropped", "mqtt: 0 lost"}});
    lp::cli::ViewState state;
    state.shading.background = true;  // no panorama is set: the model is drawn on black
    const lp::cli::HudLayout layout = lp::cli::hudLayout(fb);
    renderer.draw(fb, lp::cli::framedBesideHud(state.camera, layout, true), state.shading);
    const auto before = lp::gl::Renderer::readRgb8(fb);
    hud.draw(layout, renderer, state, 16.0);
    const auto after = lp::gl::Renderer::readRgb8(fb);
    ASSERT_EQ(before.size(), after.size());

    std::size_t model = 0, covered = 0, changed = 0;
    for (std::size_t i = 0; i < before.size(); i += 3) {
      const bool isModel = before[i] > 8 || before[i + 1] > 8 || before[i + 2] > 8;
      const bool same = std::equal(&before[i], &before[i] + 3, &after[i]);
      model += isModel;
      covered += isModel && !same;
      changed += !same;
    }
    EXPECT_GT(model, before.size() / 3 / 50) << "the model is hardly visible";
    EXPECT_EQ(covered, 0u) << "the HUD covers " << covered << " of the model's " << model
                           << " pixels";
    if (layout.status) {
      EXPECT_GT(changed, 0u) << "no HUD drawn";
    }
    for (const auto& p : hud.panels()) {
      SCOPED_TRACE(p.name);
      EXPECT_GE(p.min.x, 0.0f);
      EXPECT_GE(p.min.y, 0.0f);
      EXPECT_LE(p.max.x, float(fb.x));
      EXPECT_LE(p.max.y, float(fb.y));
      EXPECT_LE(p.contentHeight, p.max.y - p.min.y + 1.0f) << "the panel's content is cut";
      if (p.name != "liveprobe") continue;
      int checkMark = 0;
      for (int y = int(p.min.y); y < int(p.max.y); ++y)
        for (int x = int(p.min.x); x < int(p.max.x); ++x) {
          const std::uint8_t* c = &after[3 * (std::size_t(y) * std::size_t(fb.x) + std::size_t(x))];
          checkMark += c[0] < 75 && c[1] >= 130 && c[1] <= 160 && c[2] > 215;
        }
      EXPECT_EQ(checkMark, 0) << "a window control is drawn headless";
    }
  }
}

// Dynamic resolution against a model of a software rasterizer: a frame costs a fixed 6 ms plus
// 120 ms for the full-size view, 60 of it without MSAA, scaling with the view's pixels (the scale
// squared). Kept at 30 frames/s, the controller drops MSAA, then finds the scale whose frame
// time meets the target, and gives the resolution back when the cost falls.
TEST(DynamicResolution, KeepsTheFrameRateOfASoftwareRasterizer) {
  EXPECT_TRUE(lp::gl::isSoftwareRenderer("GLFW window, llvmpipe (LLVM 15.0.6, 256 bits), GL 4.5"));
  EXPECT_TRUE(lp::gl::isSoftwareRenderer("OSMesa offscreen, softpipe, GL 3.3"));
  EXPECT_FALSE(
      lp::gl::isSoftwareRenderer("GLFW window, NVIDIA GeForce RTX 4090/PCIe/SSE2, GL 4.6"));

  const double target = 1000.0 / 30.0;
  lp::cli::DynamicResolution d(true, target);
  double viewMs = 120;  // the full-size view with 4x MSAA
  auto frame = [&] {
    lp::gl::ShadingSettings s;
    s.samples = 4;
    s = d.apply(s);
    const double view = viewMs * (s.samples > 1 ? 1.0 : 0.5) * s.renderScale * s.renderScale;
    return 6.0 + view;
  };
  for (int i = 0; i < 200; ++i) d.update(frame());
  EXPECT_TRUE(d.msaaOff());
  // The scale that meets the target is sqrt((33.3 - 6) / 60) = 0.675: within a step below it.
  EXPECT_LE(frame(), 1.1 * target) << "scale " << d.scale();
  EXPECT_GT(d.scale(), 0.675f * 0.75f);
  EXPECT_LT(d.scale(), 0.675f * 1.1f);
  EXPECT_NE(d.describe().find("software GL: 3D view at"), std::string::npos);
  viewMs = 20;  // a lighter scene: the full size comes back
  for (int i = 0; i < 400; ++i) d.update(frame());
  EXPECT_FLOAT_EQ(d.scale(), 1.0f);
  // An impossible target ends at the smallest scale, never below it.
  viewMs = 5000;
  for (int i = 0; i < 400; ++i) d.update(frame());
  EXPECT_GE(d.scale(), 0.3f);
  EXPECT_LT(d.scale(), 0.31f);
  // Inactive (a GPU, or headless), it changes nothing.
  lp::cli::DynamicResolution off(false);
  for (int i = 0; i < 50; ++i) off.update(500);
  lp::gl::ShadingSettings s;
  s.samples = 4;
  EXPECT_EQ(off.apply(s).samples, 4);
  EXPECT_EQ(off.apply(s).renderScale, 1.0f);
  EXPECT_EQ(off.describe(), "");
}

// ---- the look -----------------------------------------------------------------------------------

// The restatement's figure (one coefficient, the others zero) must be visible with the defaults:
// auto exposure comes from the irradiance when there is no environment.
TEST(Look, SingleCoefficientFiguresAreVisibleWithDefaults) {
  lpt::TempDir tmp;
  for (const auto name : lp::kShNames) {
    // Positive values, and the README's L20=-0.2 (a negative L11, say, lights only the far side).
    for (const char* value : {"0.2", "-0.2"}) {
      if (value[0] == '-' && name != "L20") continue;
      const std::string out = tmp / (std::string(name) + value + ".png");
      const auto r = runLiveprobe("render --headless --size 160x120 --coeff " + std::string(name) +
                                  "=" + value + " --out " + out);
      ASSERT_EQ(r.exitCode, 0) << r.output;
      const cv::Mat img = cv::imread(out, cv::IMREAD_GRAYSCALE);
      ASSERT_FALSE(img.empty());
      double hi = 0;
      cv::minMaxLoc(img, nullptr, &hi);
      EXPECT_GT(hi, 127.5) << name << "=" << value << ": brightest pixel " << hi
                           << " is below 50% grey";
    }
  }
}

// An 8-bit panorama is shown as the source looks (display-referred): a background pixel equals
// the source's pixel in that direction, within a few codes (bilinear filtering of a smooth
// gradient); with --tonemap-background it is exposed and tone-mapped instead.
TEST(Look, EightBitBackgroundIsShownAsTheSourceLooks) {
  lpt::TempDir tmp;
  const int w = 512, h = 256;
  cv::Mat src(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      src.at<cv::Vec3b>(y, x) =
          cv::Vec3b(std::uint8_t(40 + y * 150 / h), 90, std::uint8_t(30 + x * 200 / w));
  ASSERT_TRUE(cv::imwrite(tmp / "pano.png", src));
  const int W = 480, H = 270;
  // A screen pixel right of the model, on the horizon row: its world direction
  // (liveprobe/sh/axes.h), then its equirect pixel (liveprobe/sh/sh.h).
  const int sx = 440, sy = 135;
  const float tanHalf = std::tan(glm::radians(20.0f)), aspect = float(W) / H;
  const glm::vec3 g = glm::normalize(glm::vec3((2 * (sx + 0.5f) / W - 1) * tanHalf * aspect,
                                               (1 - 2 * (sy + 0.5f) / H) * tanHalf, -1));
  const glm::vec3 d(g.z, -g.x, g.y);
  const float t = std::acos(d.z),
              p = std::fmod(std::atan2(d.y, d.x) + 2 * float(M_PI), 2 * float(M_PI));
  const cv::Vec3b want = src.at<cv::Vec3b>(int(t / M_PI * h), int(p / (2 * M_PI) * w));
  for (const char* cmd : {"replay", "render"}) {
    const std::string args = std::string(cmd) + " --headless --msaa 1 --size 480x270 " +
                             (std::string(cmd) == "replay"
                                  ? tmp / "pano.png" + " --frames 1 --quiet --out-dir " + tmp / "r"
                                  : "--env " + tmp / "pano.png" + " --out " + tmp / "r.png");
    const auto r = runLiveprobe(args);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const cv::Mat img =
        cv::imread(std::string(cmd) == "replay" ? tmp / "r/frame_000000.png" : tmp / "r.png");
    ASSERT_FALSE(img.empty());
    const cv::Vec3b got = img.at<cv::Vec3b>(sy, sx);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 4) << cmd << ": channel " << c;
    const auto tm = runLiveprobe(args + " --tonemap-background");
    ASSERT_EQ(tm.exitCode, 0) << tm.output;
    const cv::Mat img2 =
        cv::imread(std::string(cmd) == "replay" ? tmp / "r/frame_000000.png" : tmp / "r.png");
    EXPECT_GT(cv::norm(cv::Vec3d(img2.at<cv::Vec3b>(sy, sx)) - cv::Vec3d(want)), 10)
        << cmd << ": not tone-mapped";
  }
}

// ---- orientation --------------------------------------------------------------------------------

// An HDR equirect, dim everywhere but for a small bright spot at file direction f.
// The spot is a Gaussian of 0.6 degrees around f, evaluated at each pixel centre (the equirect
// convention of liveprobe/sh/sh.h), so its centroid is f to well under a pixel.
void writeSpotMap(const std::string& path, glm::vec3 f) {
  const int w = 1024, h = 512;
  cv::Mat m(h, w, CV_32FC3, cv::Scalar(0.05, 0.05, 0.05));
  const double sigma = 0.6 * M_PI / 180;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double t = M_PI * (y + 0.5) / h, p = 2 * M_PI * (x + 0.5) / w;
      const glm::dvec3 d(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
      const double a = std::acos(std::clamp(glm::dot(d, glm::dvec3(f)), -1.0, 1.0));
      if (a < 4 * sigma)
        m.at<cv::Vec3f>(y, x) +=
            cv::Vec3f::all(float(3000 * std::exp(-0.5 * a * a / (sigma * sigma))));
    }
  ASSERT_TRUE(cv::imwrite(path, m));
}

// Centroid of the pixels within 2% of the brightest, among those `mask` selects.
cv::Point2d brightest(const cv::Mat& gray, const cv::Mat& mask) {
  double hi = 0;
  cv::minMaxLoc(gray, nullptr, &hi, nullptr, nullptr, mask);
  double sx = 0, sy = 0, n = 0;
  for (int y = 0; y < gray.rows; ++y)
    for (int x = 0; x < gray.cols; ++x)
      if (mask.at<std::uint8_t>(y, x) && gray.at<std::uint8_t>(y, x) >= 0.98 * hi)
        sx += x, sy += y, n += 1;
  return {sx / std::max(n, 1.0), sy / std::max(n, 1.0)};
}

// --env-rotate (and --env-flip) turn the lighting and the background by the same rotation: the
// spot shows where perspective puts its world direction, and the sphere's brightest point faces
// it. The world direction is chosen in view; the file direction is solved from it, so each
// rotation is checked against geometry, not against liveprobe's own output.
TEST(Orientation, EnvRotateTurnsLightingAndBackgroundTogether) {
  lpt::TempDir tmp;
  const int W = 480, H = 270;
  const glm::vec3 gl = glm::normalize(
      glm::vec3(0.45f, 0.25f, -1.0f));  // right of and above straight ahead, clear of the sphere
  const glm::vec3 world(gl.z, -gl.x, gl.y);  // liveprobe/sh/axes.h
  const float tanHalf = std::tan(glm::radians(20.0f)), aspect = float(W) / H;
  const cv::Point2d expected(W / 2.0 * (1 + gl.x / -gl.z / (tanHalf * aspect)),
                             H / 2.0 * (1 - gl.y / -gl.z / tanHalf));
  struct Case {
    float yaw, pitch, roll;
    bool flip;
  };
  for (const Case c : {Case{0, 0, 0, false}, Case{90, 0, 0, false}, Case{30, 20, 10, false},
                       Case{-45, -10, 0, true}}) {
    glm::mat3 o = lp::rotationYawPitchRoll(c.yaw, c.pitch, c.roll);
    if (c.flip) o = o * glm::mat3(glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, 0, -1));
    const glm::vec3 f = glm::transpose(o) * world;  // O is orthogonal
    const std::string map = tmp / "spot.hdr";
    writeSpotMap(map, f);
    char rot[96];
    std::snprintf(rot, sizeof rot, " --env-rotate=%g,%g,%g%s", c.yaw, c.pitch, c.roll,
                  c.flip ? " --env-flip" : "");
    const std::string args = "render --headless --msaa 1 --size 480x270 --env " + map + rot;
    ASSERT_EQ(runLiveprobe(args + " --out " + tmp / "bg.png").exitCode, 0);
    const auto r = runLiveprobe(args + " --no-background --out " + tmp / "model.png");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const cv::Mat bg = cv::imread(tmp / "bg.png", cv::IMREAD_GRAYSCALE),
                  model = cv::imread(tmp / "model.png", cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(bg.empty());
    const cv::Mat onModel = model > 0, offModel = model == 0;
    const cv::Point2d spot = brightest(bg, offModel), lit = brightest(model, onModel);
    EXPECT_LT(cv::norm(spot - expected), 2.5)
        << rot << ": the spot is drawn at " << spot << ", geometry says " << expected;
    const cv::Point2d centre(W / 2.0, H / 2.0);
    const double a = std::atan2(spot.y - centre.y, spot.x - centre.x),
                 b = std::atan2(lit.y - centre.y, lit.x - centre.x);
    const double diff = std::abs(std::remainder(a - b, 2 * M_PI)) * 180 / M_PI;
    EXPECT_LT(diff, 10.0) << rot << ": the sphere's brightest point " << lit
                          << " does not face the spot " << spot;
  }
}

// --env-flip on coeffs negates exactly the coefficients odd in z (an independent rule).
TEST(Orientation, FlipNegatesTheCoefficientsOddInZ) {
  const std::string grace = lpt::dataPath("probes/latlong_256x128/grace.hdr");
  const auto a = runLiveprobe("coeffs " + grace), b = runLiveprobe("coeffs --env-flip " + grace);
  ASSERT_EQ(a.exitCode, 0) << a.output;
  ASSERT_EQ(b.exitCode, 0) << b.output;
  const auto ja = nlohmann::json::parse(a.output)["coefficients"],
             jb = nlohmann::json::parse(b.output)["coefficients"];
  const double scale = ja["L00"][1].get<double>();
  for (const auto name : lp::kShNames) {
    const bool odd = name == "L10" || name == "L2-1" || name == "L21";
    for (int ch = 0; ch < 3; ++ch)
      EXPECT_NEAR(jb[std::string(name)][ch].get<double>(),
                  (odd ? -1 : 1) * ja[std::string(name)][ch].get<double>(), 1e-5 * scale)
          << name;
  }
}

// ---- clean stops and progress -------------------------------------------------------------------

TEST(Stops, SigintDuringHeadlessReplayLeavesCompleteOutputs) {
  lpt::TempDir tmp;
  const std::string d = tmp.path.string();
  const auto r = runShell(
      "\"$LP\" replay synthetic:128x64@30 --headless --msaa 1 --size 160x90 --coeffs-out " + d +
      "/c.jsonl --out-dir " + d +
      "/frames & pid=$!; sleep 3; kill -INT $pid; wait $pid; echo rc=$?");
  EXPECT_NE(r.output.find("rc=130"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frames captured"), std::string::npos) << "no summary: " << r.output;
  EXPECT_NE(r.output.find("until Ctrl-C"), std::string::npos)
      << "an endless source must say so: " << r.output;
  std::ifstream in(d + "/c.jsonl");
  ASSERT_TRUE(in) << "--coeffs-out was not finalised";
  std::size_t lines = 0;
  for (std::string line; std::getline(in, line); ++lines) {
    const auto j = nlohmann::json::parse(line);  // every line complete
    EXPECT_EQ(j["frame"].get<std::size_t>(), lines);
  }
  std::size_t pngs = 0;
  for (const auto& e : fs::directory_iterator(d + "/frames"))
    pngs += e.path().extension() == ".png";
  EXPECT_GT(lines, 0u);
  EXPECT_EQ(lines, pngs) << "every frame drawn is written, and listed";
  for (const auto& e : fs::recursive_directory_iterator(d))
    EXPECT_NE(e.path().filename().string()[0], '.') << "left behind: " << e.path();
}

// A paced replay waits for each frame's time on the capture thread: a signal ends that wait at
// once (a still at 0.02 frames/s waits 50 s a frame; served replays are paced too).
TEST(Stops, SignalDuringAPacedWaitEndsTheRunAtOnce) {
  lpt::TempDir tmp;
  const std::string d = tmp.path.string();
  const std::string still = lpt::dataPath("probes/latlong_256x128/grace.hdr");
  for (const char* sig : {"INT", "TERM"}) {
    const auto r = runShell("cd " + lpt::shellQuote(d) + "; \"$LP\" replay " + still +
                            " --fps 0.02 --loop --headless --realtime --msaa 1 --size 96x54 "
                            "--coeffs-out c.jsonl 2>err.txt & pid=$!; for i in $(seq 200); do "
                            "grep -q Ctrl-C err.txt && break; sleep 0.1; done; sleep 1; "
                            "rm err.txt; t0=$(date +%s%N); kill -" +
                            sig +
                            " $pid; wait $pid; echo rc=$? ms=$(( ($(date +%s%N) - t0) / "
                            "1000000 ))");
    EXPECT_NE(r.output.find("rc=130"), std::string::npos) << sig << ": " << r.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(r.output, m, std::regex("ms=(\\d+)"))) << r.output;
    // The wait polls every 20 ms; the rest is the summary and finalising (a loaded machine).
    EXPECT_LT(std::stoi(m[1]), 2000) << sig << ": the paced wait did not end: " << r.output;
    std::ifstream in(d + "/c.jsonl");
    EXPECT_TRUE(in) << "--coeffs-out was not finalised";
    for (const auto& e : fs::directory_iterator(d))
      EXPECT_NE(e.path().filename().string()[0], '.') << "left behind: " << e.path();
  }
}

// A recording whose sidecar timestamps jump by days is played with the gap shortened to one
// frame interval, and says so, instead of waiting the days out.
TEST(Stops, ATimestampGapBeyondReasonIsShortenedWithAWarning) {
  lpt::TempDir tmp;
  const std::string rec = tmp / "r.mkv";
  ASSERT_EQ(lpt::runLiveprobe("record synthetic:64x32@30 --frames 4 --quiet --out " + rec).exitCode,
            0);
  std::ifstream in(rec + ".json");
  auto j = nlohmann::json::parse(in);
  in.close();
  j["timestamps"] = {0.0, 1e6, 2e6, 2e6 + 1.0 / 30};
  std::ofstream(rec + ".json") << j.dump();
  const auto r = lpt::runCommand("timeout 20 " + std::string(LIVEPROBE_BIN) + " replay " + rec +
                                 " --headless --realtime --msaa 1 --size 96x54");
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("warning: 2 gap(s) in the source's timestamps over 10 s"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("4 frames captured"), std::string::npos) << r.output;
}

/// The files in `dir` (and below) whose names start with a dot: temporaries left behind.
std::vector<std::string> leftBehind(const std::string& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string()[0] == '.') out.push_back(e.path().string());
  return out;
}

// The handlers are the program's first act (a constructor ahead of every static initialiser of
// the binary): a signal at any moment from then on, the first milliseconds of start-up too, is
// the clean stop (exit 130, or 129 for SIGHUP, outputs final, nothing half-written left), never
// the default action's death. (Before it only the dynamic loader runs: nothing of liveprobe's.)
TEST(Stops, ASignalAtAnyMomentIsACleanStop) {
  lpt::TempDir tmp;
  const std::string d = tmp.path.string();
  const std::string commands[] = {
      "replay synthetic:64x32@30 --headless --msaa 1 --size 64x36 --coeffs-out c.jsonl "
      "--frames 100000",
      "record synthetic:256x128@30 --frames 100000 --out seq/%04d.exr"};
  for (const std::string& command : commands)
    for (const char* delay : {"0", "0.01", "0.05", "0.2", "0.5"})
      for (const char* sig : {"INT", "HUP"}) {
        const auto r =
            runShell("cd " + lpt::shellQuote(d) + "; rm -rf seq c.jsonl; mkdir seq; \"$LP\" " +
                     command + " 2>/dev/null & pid=$!; " + kAwaitSigintHandler + "sleep " + delay +
                     "; kill -" + sig + " $pid; wait $pid; echo rc=$?");
        const std::string want = std::string(sig) == "HUP" ? "rc=129" : "rc=130";
        EXPECT_NE(r.output.find(want), std::string::npos)
            << command << ", SIG" << sig << " after " << delay << " s: " << r.output;
        EXPECT_EQ(leftBehind(d), std::vector<std::string>{}) << command << " after " << delay;
        std::ifstream in(d + "/c.jsonl");
        for (std::string line; in && std::getline(in, line);) {
          EXPECT_NO_THROW(std::ignore = nlohmann::json::parse(line)) << "cut short: " << line;
        }
      }
}

// A second signal hurries the stop: the process ends at once, with the temporaries of what it
// had not finished removed (the recording, its sidecar, --coeffs-out); a third changes nothing.
TEST(Stops, ASecondSignalLeavesNoTemporaries) {
  lpt::TempDir tmp;
  const std::string d = tmp.path.string();
  for (int round = 0; round < 4; ++round) {
    const auto r = runShell(
        "cd " + lpt::shellQuote(d) +
        "; rm -f v.mkv v.mkv.json; \"$LP\" record synthetic:1024x512@30 --frames 100000 --out "
        "v.mkv "
        "2>/dev/null & pid=$!; for i in $(seq 300); do ls -a | grep -q '^\\.v\\.tmp' && break; "
        "sleep 0.02; done; sleep 0." +
        std::to_string(2 + round) +
        "; kill -INT $pid; sleep 0.005; kill -INT $pid; kill -INT $pid; "
        "wait $pid; echo rc=$?");
    EXPECT_NE(r.output.find("rc=130"), std::string::npos) << r.output;
    EXPECT_EQ(leftBehind(d), std::vector<std::string>{}) << "round " << round;
  }
  const auto r = runShell("cd " + lpt::shellQuote(d) +
                          "; \"$LP\" replay synthetic:64x32@30 --headless --msaa 1 --size 64x36 "
                          "--coeffs-out c.jsonl --frames 100000 2>/dev/null & pid=$!; sleep 0.5; "
                          "kill -HUP $pid; kill -HUP $pid; wait $pid; echo rc=$?");
  EXPECT_NE(r.output.find("rc=129"), std::string::npos) << r.output;
  EXPECT_EQ(leftBehind(d), std::vector<std::string>{});
}

#if LIVEPROBE_WITH_MQTT
// With no broker there (plain or TLS), the run ends when its summary is out: the MQTT client's
// thread, asleep in a reconnect's backoff or a handshake, does not hold the exit for seconds.
// Timed from the summary's line to the exit, which a loaded machine lengthens by little.
TEST(Stops, ARunWithNoBrokerEndsAtItsSummary) {
  for (const char* scheme : {"mqtt", "mqtts"}) {
    const auto r = runShell(
        "python3 -c 'import subprocess, sys, time\n"
        "p = subprocess.Popen(sys.argv[1:], stderr=subprocess.PIPE, text=True)\n"
        "t = None\n"
        "for line in p.stderr:\n"
        "    if \"reached the broker\" in line: t = time.monotonic()\n"
        "p.wait()\n"
        "print(\"gap=%.2f\" % (time.monotonic() - t) if t else \"no summary\")' "
        "\"$LP\" replay synthetic:64x32@30 --headless --msaa 1 --size 64x36 --frames 10 "
        "--publish " +
        std::string(scheme) + "://127.0.0.1:1/t");
    std::smatch m;
    ASSERT_TRUE(std::regex_search(r.output, m, std::regex(R"(gap=([0-9.]+))"))) << r.output;
    EXPECT_LT(std::stod(m[1]), 4.0) << scheme << ": the exit waited after the summary";
  }
}

// The wait for an MQTT broker (up to 3 s for one that accepts the connection and does not answer
// yet) wakes on a stop: the run ends without waiting it out, so the warning the wait's end
// prints never comes, and the summary does.
TEST(Stops, ASignalEndsTheWaitForABroker) {
  const auto r = runShell(
      "exec 3< <(python3 -c 'import socket, time; s = socket.socket(); "
      "s.bind((\"127.0.0.1\", 0)); s.listen(); print(s.getsockname()[1], flush=True); "
      "time.sleep(20)'); py=$!; read port <&3; \"$LP\" replay synthetic:64x32@30 --headless --msaa "
      "1 "
      "--size 64x36 --frames 100000 --publish mqtt://127.0.0.1:$port/t 2>err.txt & pid=$!; " +
      kAwaitSigintHandler +
      "sleep 0.5; kill -INT $pid; wait $pid; "
      "echo rc=$?; cat err.txt; rm -f err.txt; kill $py");
  EXPECT_NE(r.output.find("rc=130"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("no broker answers yet"), std::string::npos)
      << "the wait was not cut short: " << r.output;
  EXPECT_NE(r.output.find("frames captured"), std::string::npos) << "no summary: " << r.output;
}
#endif

// The brute-force integral of a large map takes minutes; a signal stops it between normals at
// once: exit 130, a line that says how far it got, and no output file.
TEST(Stops, ASignalStopsTheBruteForceIntegral) {
  lpt::TempDir tmp;
  const std::string out = (tmp.path / "E.exr").string();
  const auto r = runShell("\"$LP\" irradiance " +
                          lpt::shellQuote(lpt::dataPath("equirect/venice_sunset_1k.hdr")) +
                          " --method brute --size 512x256 --out " + lpt::shellQuote(out) +
                          " & pid=$!; " + kAwaitSigintHandler +
                          "sleep 1.5; kill -INT $pid; s=$SECONDS; wait $pid; echo rc=$? "
                          "waited=$((SECONDS - s))");
  EXPECT_NE(r.output.find("rc=130"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("irradiance stopped by a signal after"), std::string::npos) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex(R"(waited=(\d+))"))) << r.output;
  EXPECT_LE(std::stoi(m[1]), 5) << "the stop waited for the integral: " << r.output;
  EXPECT_FALSE(fs::exists(out)) << r.output;
  for (const auto& f : fs::directory_iterator(tmp.path))
    ADD_FAILURE() << "left behind: " << f.path();
}

// Counts that add up however a run is stopped: frames captured = drawn + dropped, records
// offered to the broker (published + lost) = captured, and --coeffs-out's lines = the records
// the summary counts. A
// replay that publishes is paced: a stop during a frame's wait must neither count nor send it.
TEST(Stops, CountsAddUpWhereverTheRunIsStopped) {
  lpt::TempDir tmp;
  const std::string d = tmp.path.string();
  const std::string publish = LIVEPROBE_WITH_MQTT ? " --publish mqtt://127.0.0.1:1/t" : "";
  for (const char* delay : {"0.4", "0.9", "1.3", "2.1"}) {
    const auto r = runShell("cd " + lpt::shellQuote(d) +
                            "; rm -f c.jsonl; \"$LP\" replay synthetic:64x32@30 --headless "
                            "--msaa 1 --size 64x36 --realtime --frames 100000 --coeffs-out "
                            "c.jsonl" +
                            publish + " & pid=$!; " + kAwaitSigintHandler + "sleep " + delay +
                            "; kill -INT $pid; wait $pid; echo rc=$?");
    ASSERT_NE(r.output.find("rc=130"), std::string::npos) << r.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(
        r.output, m, std::regex(R"((\d+) frames captured, (\d+) drawn, (\d+) dropped)")))
        << r.output;
    const int captured = std::stoi(m[1]), drawn = std::stoi(m[2]), dropped = std::stoi(m[3]);
    EXPECT_EQ(captured, drawn + dropped) << delay << " s: " << r.output;
    if (LIVEPROBE_WITH_MQTT) {
      ASSERT_TRUE(std::regex_search(r.output, m, std::regex(R"((\d+) published, (\d+) lost)")))
          << r.output;
      EXPECT_EQ(std::stoi(m[1]) + std::stoi(m[2]), captured) << delay << " s: " << r.output;
    }
    std::ifstream in(d + "/c.jsonl");
    int lines = 0;
    for (std::string line; std::getline(in, line);) ++lines;
    // With a network sink every record offered is a line (drawn or sent only); without one,
    // headless --coeffs-out lists the frames drawn.
    EXPECT_EQ(lines, LIVEPROBE_WITH_MQTT ? captured : drawn) << delay << " s: " << r.output;
  }
}

// A still's background is the frame path's (FrameProcessor::run), byte for byte, as the stream's
// is: an 8-bit map the display decodes is the frame itself, a float map its linear copy.
TEST(Background, StillsDrawFrameProcessorRunsBackground) {
  lpt::TempDir tmp;
  std::vector<std::uint8_t> rgb(64 * 32 * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = std::uint8_t((i * 53) % 256);
  const std::string png = tmp / "pano.png";
  lp::saveRgb8(png, 64, 32, rgb.data());
  for (const std::string& file : {png, lpt::dataPath("probes/latlong_256x128/grace.hdr")}) {
    SCOPED_TRACE(file);
    const lp::cli::Environment env =
        lp::cli::loadEnvironment(file, lp::cli::PanoramaSettings{}, {.maxLights = 0}, true);
    auto frame = std::make_shared<lp::Frame>();
    ASSERT_TRUE(lp::openSource(file)->next(*frame));
    lp::FrameProcessor processor({lp::LayoutSpec(lp::Layout::Equirect)});
    const lp::Background b = processor.run(frame, {.background = true}).background;
    const lp::Background& a = env.background;
    ASSERT_EQ(bool(a.raw), frame->format == lp::PanoramaFormat::BgrU8);
    ASSERT_EQ(bool(a.raw), bool(b.raw));
    EXPECT_EQ(a.scale, b.scale);
    EXPECT_EQ(a.layout, b.layout);
    if (a.raw)
      EXPECT_EQ(a.raw->bgr8, b.raw->bgr8);
    else
      EXPECT_EQ(a.image->rgb, b.image->rgb);
  }
}

// Headless --coeffs-out is a record sink like the stream and the broker: a line for each frame
// as it is drawn, with its render time; beside a network sink, the records sent at capture and
// never drawn follow at stop(), in frame order, with render time null; alone, only drawn frames.
TEST(RecordSinks, HeadlessCoeffsOutLogsDrawnFramesThenTheSentOnes) {
  struct Network final : lp::RecordSink {  // stands for --serve or --publish: takes every record
    int records = 0;
    void publish(lp::FrameRecord&) override { ++records; }
  };
  lpt::TempDir tmp;
  const lp::CoeffFormat format = lp::parseCoeffFormat("json", "--coeffs-format", true);
  const auto run = [&](bool network) {
    const std::string path = tmp / (network ? "net.jsonl" : "alone.jsonl");
    lp::AtomicTextFile file(path);
    lp::cli::RecordSinks sinks;
    if (network) sinks.all.push_back(std::make_unique<Network>());
    lp::cli::addCoeffsSink(sinks, file, format, lp::cli::CoeffsLines::AtDraw);
    std::vector<lp::ProcessedFrame> frames(4);
    for (std::size_t i = 0; i < frames.size(); ++i) {
      frames[i].index = i + 1;
      lp::FrameRecord record(frames[i], format);
      for (auto& sink : sinks.all) sink->publish(record);
    }
    sinks.shown(frames[0], {2.5, 30.0});
    sinks.shown(frames[2], {3.5, 31.0});  // frame 2 was dropped before drawing
    for (auto& sink : sinks.all) sink->stop();
    file.commit();
    std::vector<nlohmann::json> lines;
    std::ifstream in(path);
    for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
    return lines;
  };
  const auto net = run(true);
  ASSERT_EQ(net.size(), 3u);  // drawn 1 and 3, then 4 (sent, never drawn); 2 was dropped
  EXPECT_EQ(net[0]["frame"], 1);
  EXPECT_EQ(net[0]["timings_ms"]["render"], 2.5);
  EXPECT_EQ(net[0]["latency_ms"]["shown"], 30.0);
  EXPECT_EQ(net[1]["frame"], 3);
  EXPECT_EQ(net[1]["timings_ms"]["render"], 3.5);
  EXPECT_EQ(net[2]["frame"], 4);
  EXPECT_TRUE(net[2]["timings_ms"]["render"].is_null());
  EXPECT_FALSE(net[2]["latency_ms"].contains("shown"));
  const auto alone = run(false);
  ASSERT_EQ(alone.size(), 2u);
  EXPECT_EQ(alone[0]["frame"], 1);
  EXPECT_EQ(alone[1]["frame"], 3);
}

TEST(Stops, SigintDuringRecordFinalisesTheRecording) {
  lpt::TempDir tmp;
  const std::string out = tmp / "rec.mkv";
  const auto r = runShell("\"$LP\" record synthetic:64x32@30 --frames 100000 --out " + out +
                          " & pid=$!; sleep 2; kill -TERM $pid; wait $pid; echo rc=$?");
  EXPECT_NE(r.output.find("rc=130"), std::string::npos) << r.output;
  cv::VideoCapture cap(out);
  ASSERT_TRUE(cap.isOpened()) << "the recording was not finalised: " << r.output;
  EXPECT_GT(cap.get(cv::CAP_PROP_FRAME_COUNT), 1);
  EXPECT_TRUE(fs::exists(out + ".json"));
}

TEST(Progress, HeadlessRunsReportFramesRateAndEta) {
  lpt::TempDir tmp;
  const auto r = runShell(
      "LIVEPROBE_PROGRESS_SECONDS=0.05 \"$LP\" replay synthetic:64x32@30 --headless --msaa 1 "
      "--size 64x36 --frames 40");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  // 40 frames take 0.2-0.5 s here: a report every 0.05 s shows at least one.
  EXPECT_TRUE(std::regex_search(r.output, std::regex(R"(replay: \d+/40 frames, [0-9.]+/s, ETA)")))
      << r.output;
  const auto q = runShell(
      "LIVEPROBE_PROGRESS_SECONDS=0.2 \"$LP\" replay synthetic:64x32@30 --headless --msaa 1 "
      "--size 64x36 --frames 40 --quiet");
  EXPECT_EQ(q.output.find("/40 frames"), std::string::npos) << q.output;
  // A file of known length: its total and an ETA without --frames (the recording's 150 frames).
  const auto f = runShell("LIVEPROBE_PROGRESS_SECONDS=0.05 \"$LP\" replay " +
                          std::string(LIVEPROBE_SOURCE_DIR) +
                          "/recordings/sky.mkv --headless --msaa 1 --size 64x36");
  ASSERT_EQ(f.exitCode, 0) << f.output;
  EXPECT_TRUE(std::regex_search(f.output, std::regex(R"(replay: \d+/150 frames, [0-9.]+/s, ETA)")))
      << f.output;
}

// ---- the command line ---------------------------------------------------------------------------

TEST(CommandLine, EveryHelpNamesEveryOptionItAccepts) {
  for (const auto& c : lp::cli::commands()) {
    const auto r = runLiveprobe(c.spec.name + " --help");
    EXPECT_EQ(r.exitCode, 0) << c.spec.name;
    for (const auto& o : c.spec.options) {
      std::size_t start = 0;
      while (start < o.name.size()) {  // "--env-rotate,--rotate": every name
        const auto comma = o.name.find(',', start);
        const std::string one =
            o.name.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        EXPECT_NE(r.output.find(one), std::string::npos)
            << c.spec.name << " --help does not name " << one;
        start = comma == std::string::npos ? o.name.size() : comma + 1;
      }
    }
  }
}

// An option name means one thing in every command that takes it: the same typed field, whatever
// the command's own help, range and default. Every command that takes --size, --frames, --fps,
// --out or --format is given it, and the one field it names must hold the value.
TEST(CommandLine, EachOptionNameSetsOneField) {
  using lp::cli::Settings;
  struct Shared {
    std::string name;
    std::vector<std::string> values;  ///< the first a command accepts is given
    std::function<bool(const Settings&, const std::string&)> holds;
  };
  const std::vector<Shared> shared = {
      {"--size",
       {"40x20"},
       [](const Settings& s, const std::string&) {
         return s.output.size == lp::cli::Size{40, 20};
       }},
      {"--frames",
       {"7"},
       [](const Settings& s, const std::string&) { return s.output.frames == 7; }},
      {"--fps", {"25"}, [](const Settings& s, const std::string&) { return s.stream.fps == 25.0; }},
      {"--out",
       {"x.png", "x.mkv", "x.json"},
       [](const Settings& s, const std::string& v) { return s.output.out == v; }},
      // the printed form: coeffs takes any coefficient format, compare text or json
      {"--format",
       {"json"},
       [](const Settings& s, const std::string&) {
         return s.output.format && s.output.format->name == "json";
       }},
  };
  for (const auto& c : lp::cli::commands()) {
    for (const Shared& o : shared) {
      const bool takes =
          std::any_of(c.spec.options.begin(), c.spec.options.end(),
                      [&](const lp::cli::OptionSpec& x) { return x.name == o.name; });
      if (!takes) continue;
      std::string refused;
      bool given = false;
      // (a command that requires --out gets one it takes: .json, .png or .mkv)
      const std::vector<std::string> outs =
          o.name != "--out" && std::any_of(c.spec.options.begin(), c.spec.options.end(),
                                           [](const auto& x) { return x.name == "--out"; })
              ? std::vector<std::string>{"x.json", "x.png", "x.mkv"}
              : std::vector<std::string>{""};
      for (const std::string& v : o.values)
        for (const std::string& out : outs) {
          if (given) break;
          std::vector<std::string> argv = {o.name, v};
          if (!out.empty()) argv.insert(argv.end(), {"--out", out});
          for (int i = 0; i < c.spec.minPositional; ++i) argv.push_back("x");
          try {
            const lp::cli::Args a(c.spec, argv);
            EXPECT_TRUE(o.holds(a.settings(), v)) << c.spec.name << " " << o.name << " " << v;
            given = true;
          } catch (const lp::Error& e) {
            refused += std::string(e.what()) + "; ";
          }
        }
      EXPECT_TRUE(given) << c.spec.name << " " << o.name << ": " << refused;
    }
  }
  // the camera's pixel format has a name of its own
  const auto& all = lp::cli::commands();
  const auto live =
      std::find_if(all.begin(), all.end(), [](const auto& c) { return c.spec.name == "live"; });
  ASSERT_NE(live, all.end());
  const lp::cli::Args a(live->spec, {"--pixel-format", "yuyv", "/dev/video0"});
  EXPECT_EQ(a.settings().camera.format, lp::CameraFormat::Yuyv);
}

// The camera's options are capture's own settings (lp::CameraSettings), set as the line is read:
// live and calibrate hand them to the camera as they are, with the device, --size and --fps.
TEST(CommandLine, CameraOptionsAreCapturesCameraSettings) {
  static_assert(std::is_same_v<decltype(lp::cli::Settings::camera), lp::CameraSettings>);
  const auto& all = lp::cli::commands();
  for (const char* name : {"live", "calibrate"}) {
    const auto c =
        std::find_if(all.begin(), all.end(), [&](const auto& x) { return x.spec.name == name; });
    ASSERT_NE(c, all.end());
    std::vector<std::string> argv = {"--pixel-format", "nv12", "--mjpeg-reduce", "4",
                                     "--timeout",      "0.25", "/dev/video0"};
    if (std::string(name) == "calibrate") argv.insert(argv.end(), {"--out", "r.json"});
    const lp::cli::Args a(c->spec, argv);
    const lp::CameraSettings& cs = a.settings().camera;
    EXPECT_EQ(cs.format, lp::CameraFormat::Nv12) << name;
    EXPECT_EQ(cs.mjpegReduce, 4) << name;
    EXPECT_EQ(cs.timeoutMs, 250) << name;
  }
}

TEST(CommandLine, RefusalsAreOneLineWithExit1) {
  expectOneLineError("frobnicate", "frobnicate", "unknown command");
  expectOneLineError("render --coeff L00=1 --bogus", "--bogus", "unknown option");
  expectOneLineError("render --coeff L00=1 --size 64x64 --size 32x32", "--size", "more than once");
  expectOneLineError("render --coeff L00=1 --coeff L00=2", "L00", "given twice");
  expectOneLineError("render --coeff L00=1 --out x.tiff", "x.tiff", "unsupported extension");
  expectOneLineError("render --coeff L00=1 --size 100000x100000", "100000x100000", "at most 16384");
  expectOneLineError("replay --frames 0", "--frames", "expected an integer from 1");
  expectOneLineError("bench --threshold -5", "--threshold", "expected 0 to 1000");
  expectOneLineError("record synthetic --out x.mkv --fps -1", "--fps", "expected");
  const auto r = runLiveprobe("render --coeff L00=1 --bogus");
  EXPECT_EQ(r.output.rfind("liveprobe render: ", 0), 0u) << "one prefix: " << r.output;
  EXPECT_EQ(r.output.find("render: render"), std::string::npos) << r.output;
}

// Refusals that name the real fault: a size of nothing, a folder where a file goes (for --out)
// or a file where a folder goes (for --out-dir).
TEST(CommandLine, RefusalsSayWhatIsWrong) {
  lpt::TempDir tmp;
  expectOneLineError("render --coeff L00=1 --size 0x0", "0x0", "must be at least 1");
  expectOneLineError("render --coeff L00=1 --size 64x-2", "64x-2", "must be at least 1");
  expectOneLineError("render --coeff L00=1 --out " + tmp.path.string(), tmp.path.string(),
                     "is a folder; name a file (.png");
  const std::string file = tmp / "not-a-folder";
  std::ofstream(file) << "x";
  expectOneLineError("replay synthetic:64x32 --headless --frames 1 --out-dir " + file, file,
                     "is a file, not a folder");
  // A folder of panoramas is a sequence: coeffs reads one map and says so.
  const std::string folder = tmp / "maps";
  fs::create_directories(folder);
  for (const char* name : {"a.hdr", "b.hdr"})
    ASSERT_TRUE(cv::imwrite(folder + "/" + name, cv::Mat(16, 32, CV_32FC3, cv::Scalar(1, 1, 1))));
  expectOneLineError("coeffs " + folder, folder, "2 frames (a sequence or a video), not one map");
  // An engine's export given where liveprobe's own coefficients go.
  const std::string map = lpt::dataPath("probes/latlong_256x128/grace.hdr");
  for (const std::string engine : {"three", "gltf"}) {
    const std::string exported = tmp / (engine + ".json");
    const auto r = runLiveprobe("coeffs " + map + " --format " + engine);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::ofstream(exported) << r.output;
    expectOneLineError("render --coeffs " + exported + " --out " + (tmp / "x.png"), exported,
                       engine == "gltf" ? "a glTF document (--format gltf), not liveprobe's"
                                        : "an export for three (--format three), not liveprobe's");
  }
}

// A headless replay that keeps nothing says so at its end; one that keeps something, or --quiet,
// does not; a run that fails says only why. (The suite runs without a display: "no display, so
// headless" is what a user sees.)
TEST(CommandLine, AHeadlessRunThatKeepsNothingSaysSo) {
  lpt::TempDir tmp;
  const std::string run = "replay synthetic:64x32 --frames 2 --size 32x18 ";
  const auto bare = runLiveprobe(run + "--headless");
  EXPECT_EQ(bare.exitCode, 0) << bare.output;
  EXPECT_NE(bare.output.find("headless: nothing was kept from this run"), std::string::npos)
      << bare.output;
  for (const std::string& more :
       {"--headless --coeffs-out " + (tmp / "c.jsonl"), "--headless --out-dir " + (tmp / "f"),
        std::string("--headless --quiet")}) {
    const auto r = runLiveprobe(run + more);
    EXPECT_EQ(r.exitCode, 0) << more << ": " << r.output;
    EXPECT_EQ(r.output.find("nothing was kept"), std::string::npos) << more << ": " << r.output;
  }
}

// "help COMMAND" is that command's help; -V and -v are --version.
TEST(CommandLine, HelpCommandAndShortVersion) {
  const auto help = runLiveprobe("help coeffs");
  EXPECT_EQ(help.exitCode, 0) << help.output;
  EXPECT_EQ(help.output, runLiveprobe("coeffs --help").output);
  EXPECT_NE(help.output.find("--lights"), std::string::npos) << help.output;
  const auto version = runLiveprobe("--version");
  for (const char* flag : {"-V", "-v"}) {
    const auto r = runLiveprobe(flag);
    EXPECT_EQ(r.exitCode, 0) << flag << ": " << r.output;
    EXPECT_EQ(r.output, version.output) << flag;
  }
  expectOneLineError("help frobnicate", "frobnicate", "unknown command");
}

// A misspelt command or option is named with the nearest real one; an option's value that looks
// like an option is still its value, and a name far from every option gets no guess.
TEST(CommandLine, MisspellingsSuggestTheNearestName) {
  expectOneLineError("coefs x.hdr", "coefs", "did you mean coeffs?");
  expectOneLineError("coeffs x.hdr --lihgts 2", "--lihgts", "did you mean --lights?");
  expectOneLineError("replay --headles", "--headles", "did you mean --headless?");
  expectOneLineError("replay --headless --hud --no-hud --frames 1", "--no-hud", "give one");
  const auto far = runLiveprobe("coeffs x.hdr --frobnicate-everything");
  EXPECT_EQ(far.exitCode, 1) << far.output;
  EXPECT_NE(far.output.find("unknown option --frobnicate-everything"), std::string::npos)
      << far.output;
  EXPECT_EQ(far.output.find("did you mean"), std::string::npos) << far.output;
  const auto value = runLiveprobe("coeffs " + lpt::dataPath("probes/latlong_256x128/grace.hdr") +
                                  " --env-rotate=-30,0,0 --format text");
  EXPECT_EQ(value.exitCode, 0) << value.output;
}

// An option more than one command takes is declared once: one value placeholder and one help
// text wherever it appears. The exceptions are the options whose meaning is each command's own
// (what --out writes, what --size sizes, what --frames counts, ...).
TEST(OptionGroups, ASharedOptionHasOneHelpText) {
  const std::set<std::string> ownMeaning = {"--out",    "--size",     "--format",
                                            "--frames", "--duration", "--fps"};
  std::map<std::string, std::pair<const lp::cli::OptionSpec*, std::string>> first;
  int shared = 0;
  for (const auto& c : lp::cli::commands())
    for (const auto& o : c.spec.options) {
      if (ownMeaning.count(o.name)) continue;
      const auto [it, fresh] = first.emplace(o.name, std::pair{&o, c.spec.name});
      if (fresh) continue;
      ++shared;
      EXPECT_EQ(o.value, it->second.first->value)
          << o.name << " in " << c.spec.name << " and " << it->second.second;
      EXPECT_EQ(o.help, it->second.first->help)
          << o.name << " in " << c.spec.name << " and " << it->second.second;
    }
  EXPECT_GT(shared, 50);  // the layout, lighting, scene, look and light groups
}

// One meaning per option name, in kind at least: an option is a flag in every command that takes
// it, or takes a value in every one, or an optional value in every one.
TEST(OptionGroups, AnOptionIsAFlagEverywhereOrTakesAValueEverywhere) {
  const auto kind = [](const lp::cli::OptionSpec& o) {
    return o.value.empty() ? "a flag" : o.optionalValue ? "an optional value" : "a value";
  };
  std::map<std::string, std::pair<std::string, std::string>> first;  // name: kind, command
  for (const auto& c : lp::cli::commands())
    for (const auto& o : c.spec.options) {
      const auto [it, fresh] = first.emplace(o.name, std::pair{kind(o), c.spec.name});
      EXPECT_EQ(kind(o), it->second.first)
          << o.name << " takes " << kind(o) << " in " << c.spec.name << ", " << it->second.first
          << " in " << it->second.second;
    }
  EXPECT_GT(first.size(), 50u);
}

// --help writes each option's value as the reference does: an option whose value may be left out
// shows it in brackets ([SECONDS]), in every command that has one.
TEST(OptionGroups, HelpAndReferenceWriteAnOptionalValueAlike) {
  int optional = 0;
  for (const auto& c : lp::cli::commands()) {
    std::string help;
    for (const auto& o : c.spec.options)
      if (o.optionalValue && !o.value.empty()) {
        if (help.empty()) help = runLiveprobe(c.spec.name + " --help").output;
        const std::string name = o.name.substr(0, o.name.find(','));
        EXPECT_NE(help.find(name + " [" + o.value + "]"), std::string::npos)
            << c.spec.name << " --help:\n"
            << help;
        ++optional;
      }
  }
  EXPECT_GT(optional, 0);
}

// The light group in every command that takes it: the largest --lights the renderer draws is
// accepted, one more is one line naming the option and the range, a misspelling gets the name,
// and the window's --hud with --no-hud is refused in one line where both exist.
TEST(OptionGroups, TheLightGroupInEveryCommand) {
  lpt::TempDir tmp;
  const std::string map = lpt::dataPath("probes/latlong_256x128/grace.hdr");
  const std::string png = tmp / "out.png", hdr = tmp / "out.hdr";
  std::set<std::string> declaring;
  for (const auto& c : lp::cli::commands())
    for (const auto& o : c.spec.options)
      if (o.name == "--lights") declaring.insert(c.spec.name);
  // live needs a camera to get as far as its options' values; it takes the group from the same
  // declaration as replay (the test above).
  EXPECT_EQ(declaring,
            (std::set<std::string>{"coeffs", "compare", "render", "view", "replay", "live"}));
  const std::vector<std::string> commands = {
      "coeffs " + map, "compare " + map + " --size 16x8 --quiet",
      "render --env " + map + " --size 64x36 --out " + png,
      "view --env " + map + " --size 64x36 --headless --screenshot " + png,
      "replay " + map + " --headless --frames 1 --size 64x36 --quiet"};
  const std::string most = std::to_string(lp::kMaxLights);
  for (const std::string& c : commands) {
    SCOPED_TRACE(c);
    const auto ok = runLiveprobe(c + " --lights " + most);
    EXPECT_EQ(ok.exitCode, 0) << ok.output;
    expectOneLineError(c + " --lights " + std::to_string(lp::kMaxLights + 1), "--lights",
                       "1 to " + most);
    expectOneLineError(c + " --lihgts 2", "--lihgts", "did you mean --lights?");
  }
  expectOneLineError("view --env " + map + " --hud --no-hud --headless --screenshot " + png,
                     "--no-hud", "give one");
  expectOneLineError("replay " + map + " --headless --hud --no-hud --frames 1", "--no-hud",
                     "give one");
}

// Every option sets a typed field as the line is read, and where its help states a range, that
// range is the one accepted: both ends are taken (an open end only just inside it), and a step
// past either end is refused in one line that names the option.
TEST(OptionGroups, TheRangeInHelpIsTheRangeAccepted) {
  const std::regex closed(R"(\((-?[0-9.]+(?:e[+-]?[0-9]+)?) to (-?[0-9.]+(?:e[+-]?[0-9]+)?)[,)])");
  const std::regex open(
      R"(\(above (-?[0-9.]+(?:e[+-]?[0-9]+)?) and up to (-?[0-9.]+(?:e[+-]?[0-9]+)?)[,)])");
  int ranged = 0;
  for (const auto& c : lp::cli::commands())
    for (const auto& o : c.spec.options) {
      SCOPED_TRACE(c.spec.name + " " + o.name);
      ASSERT_TRUE(o.set) << "not bound to a field";
      std::smatch m;
      const bool aboveLo = std::regex_search(o.help, m, open);
      if (!aboveLo && !std::regex_search(o.help, m, closed)) continue;
      ++ranged;
      const double lo = std::stod(m[1]), hi = std::stod(m[2]);
      const std::string name = o.name.substr(0, o.name.find(','));
      auto accepts = [&](double v) {
        std::ostringstream text;
        text << std::setprecision(12) << v;
        lp::cli::Settings settings;
        try {
          o.set(settings, text.str());
          return true;
        } catch (const lp::Error& e) {
          const std::string what = e.what();
          EXPECT_EQ(what.rfind(name + " " + text.str() + ": ", 0), 0u) << what;
          EXPECT_EQ(what.find('\n'), std::string::npos) << what;
          return false;
        }
      };
      EXPECT_TRUE(accepts(hi));
      EXPECT_FALSE(accepts(hi + 1));
      EXPECT_EQ(accepts(lo), !aboveLo);
      EXPECT_FALSE(accepts(lo - 1));
      if (aboveLo) {
        EXPECT_TRUE(accepts(lo + 1e-3));
      }
    }
  EXPECT_GE(ranged, 20);  // --lights, --threads, --frames, --fps, --fov, --pitch, ...
}

TEST(CommandLine, VersionNamesTheCommit) {
  const auto r = runLiveprobe("--version");
  EXPECT_EQ(r.exitCode, 0);
  EXPECT_TRUE(std::regex_search(
      r.output, std::regex(R"(^liveprobe \d+\.\d+\.\d+ \(commit [0-9a-f]{7,}(-dirty)?\))")))
      << r.output;
}

TEST(CommandLine, LikelyLayoutMistakesWarnOnce) {
  lpt::TempDir tmp;
  const auto probe = runLiveprobe("coeffs " + lpt::dataPath("probes/beach_probe.hdr"));
  EXPECT_EQ(probe.exitCode, 0) << probe.output;
  EXPECT_NE(probe.output.find("warning: "), std::string::npos)
      << "a 640x640 probe taken as equirect: " << probe.output;
  EXPECT_NE(probe.output.find("square image taken as equirect"), std::string::npos);
  const auto video = runLiveprobe("replay " + lpt::dataPath("video/pano.mp4") +
                                  " --headless --frames 1 --quiet --msaa 1 --size 64x36");
  EXPECT_EQ(video.exitCode, 0) << video.output;
  EXPECT_NE(video.output.find("16:9 frame taken as equirect"), std::string::npos) << video.output;
  // Named: the user knows it is a stretched panorama (as pano.mp4 is), and is not warned.
  const auto named = runLiveprobe("replay " + lpt::dataPath("video/pano.mp4") +
                                  " --layout equirect --headless --frames 1 --quiet --msaa 1 "
                                  "--size 64x36");
  EXPECT_EQ(named.exitCode, 0) << named.output;
  EXPECT_EQ(named.output.find("warning"), std::string::npos) << named.output;
  const auto namedSquare =
      runLiveprobe("coeffs --layout equirect " + lpt::dataPath("probes/beach_probe.hdr"));
  EXPECT_EQ(namedSquare.output.find("warning"), std::string::npos) << namedSquare.output;
  // A square map that is bright in its corners read as an angular map.
  const std::string square = tmp / "square.hdr";
  ASSERT_TRUE(cv::imwrite(square, cv::Mat(64, 64, CV_32FC3, cv::Scalar(1, 1, 1))));
  const auto eq = runLiveprobe("coeffs --layout angular " + square);
  EXPECT_NE(eq.output.find("corners are not black"), std::string::npos) << eq.output;
  // An equirect panorama read as two fisheye lenses.
  const auto fisheye =
      runLiveprobe("coeffs --layout fisheye " + lpt::dataPath("probes/latlong_256x128/grace.hdr"));
  EXPECT_NE(fisheye.output.find("a dual fisheye frame whose corners are not black"),
            std::string::npos)
      << fisheye.output;
  // The right layout: no warning.
  const auto ok =
      runLiveprobe("coeffs --layout angular " + lpt::dataPath("probes/beach_probe.hdr"));
  EXPECT_EQ(ok.output.find("warning"), std::string::npos) << ok.output;
}

// ---- outputs ------------------------------------------------------------------------------------

TEST(Outputs, Mp4IsH264AndReadsBack) {
  lpt::TempDir tmp;
  const std::string out = tmp / "lit.mp4";
  const auto r = runLiveprobe(
      "replay synthetic:128x64@30 --frames 12 --headless --msaa 1 --size 160x90 --quiet "
      "--out-video " +
      out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  cv::VideoCapture cap(out);
  ASSERT_TRUE(cap.isOpened());
  const int fourcc = int(cap.get(cv::CAP_PROP_FOURCC));
  const std::string cc{char(fourcc & 255), char((fourcc >> 8) & 255), char((fourcc >> 16) & 255),
                       char((fourcc >> 24) & 255)};
  EXPECT_TRUE(cc == "avc1" || cc == "h264" || cc == "H264") << cc;
  int n = 0;
  for (cv::Mat f; cap.read(f);) ++n;
  EXPECT_EQ(n, 12);
}

// ---- bench
// ----------------------------------------------------------------------------------------

TEST(BenchReport, VerdictSmallStagesAndPlot) {
  lpt::TempDir tmp;
  const std::string base = tmp / "base.json";
  const std::string run = "bench synthetic:128x64@30 --frames 12 --repeat 1 --size 160x90 --quiet";
  ASSERT_EQ(runLiveprobe(run + " --json " + base).exitCode, 0);
  // A baseline whose convert stage took no time: no percentage for it.
  nlohmann::json b = nlohmann::json::parse(std::ifstream(base));
  b["stages"]["convert"]["median_ms"] = 0.0;
  std::ofstream(base) << b.dump();
  const auto r =
      runLiveprobe(run + " --baseline " + base + " --threshold 1000 --plot " + tmp / "plot.png");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_TRUE(std::regex_search(r.output,
                                std::regex(R"(verdict: no regression \(\d+ stages within 1000%)")))
      << r.output;
  EXPECT_EQ(r.output.find("1 runs"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 run of 12 frames"), std::string::npos) << r.output;
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("convert ", 0) == 0 && line.find(" vs ") != std::string::npos) {
      EXPECT_EQ(line.find('%'), std::string::npos) << "a percentage of nothing: " << line;
    }
  const cv::Mat plot = cv::imread(tmp / "plot.png");
  ASSERT_FALSE(plot.empty()) << "no plot";
  EXPECT_EQ(plot.cols, 1400);
  EXPECT_EQ(plot.rows, 480);
  for (const auto& e : fs::directory_iterator(tmp.path))
    EXPECT_NE(e.path().filename().string()[0], '.') << "left behind: " << e.path();
}

}  // namespace
