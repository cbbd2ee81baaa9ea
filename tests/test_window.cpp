// The HUD and the keys in a real GLFW window under Xvfb, driven by xdotool. Run alone (timing:
// "Esc quits within a second" is a promise about the program, not about a loaded machine).
#include <gtest/gtest.h>

#include <array>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "liveprobe/sh/sh.h"
#include "test_util.h"

namespace {

using lpt::runLiveprobe;

double meanAbsDiff(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::absdiff(a, b, d);
  const cv::Scalar m = cv::mean(d);
  return (m[0] + m[1] + m[2]) / 3;
}

// ---- a real window ------------------------------------------------------------------------------

/// Reads an X window dump (xwd -root) into BGR.
cv::Mat readXwd(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> d((std::istreambuf_iterator<char>(in)), {});
  auto be = [&](std::size_t field) {
    const unsigned char* p = d.data() + 4 * field;
    return std::uint32_t(p[0]) << 24 | std::uint32_t(p[1]) << 16 | std::uint32_t(p[2]) << 8 | p[3];
  };
  if (d.size() < 100) return {};
  const std::uint32_t headerSize = be(0), width = be(4), height = be(5), byteOrder = be(7),
                      bpp = be(11), bytesPerLine = be(12), ncolors = be(19);
  if (bpp != 24 && bpp != 32) return {};
  const std::uint32_t step =
      bpp / 8;  // Xvfb at depth 24 packs 3 bytes a pixel, rows bytesPerLine apart
  const std::size_t offset = headerSize + std::size_t(ncolors) * 12;
  if (d.size() < offset + std::size_t(bytesPerLine) * height) return {};
  cv::Mat img(int(height), int(width), CV_8UC3);
  for (std::uint32_t y = 0; y < height; ++y)
    for (std::uint32_t x = 0; x < width; ++x) {
      const unsigned char* p = d.data() + offset + std::size_t(y) * bytesPerLine + step * x;
      auto* q = img.ptr<std::uint8_t>(int(y)) + 3 * x;
      if (byteOrder == 0)
        q[0] = p[0], q[1] = p[1], q[2] = p[2];  // LSBFirst: B G R (X)
      else
        q[0] = p[step - 1], q[1] = p[step - 2], q[2] = p[step - 3];
    }
  return img;
}

int frameInTitle(const std::string& output, const std::string& key) {
  std::smatch m;
  const std::regex re(key + R"(: liveprobe - .* - frame (\d+) -)");
  return std::regex_search(output, m, re) ? std::stoi(m[1]) : -1;
}

// The HUD in a real GLFW window under Xvfb, driven by xdotool: Space pauses (the frame index in
// the title stops), H hides the HUD (and the model takes the whole frame), the exposure
// keys step once a press, and a single short tap of Esc quits.
TEST(Window, HudAndKeysUnderXvfb) {
  lpt::TempDir tmp;
  const auto run =
      lpt::runCommand(lpt::xvfbRun("1280x800x24") + std::string(LIVEPROBE_SOURCE_DIR) +
                      "/tests/scripts/window_keys.sh " + LIVEPROBE_BIN + " " + tmp.path.string());
  const std::string& out = run.output;
  ASSERT_EQ(run.exitCode, 0) << out;
  std::ifstream logf(tmp / "log");
  const std::string log((std::istreambuf_iterator<char>(logf)), {});
  const int a = frameInTitle(out, "paused_a"), b = frameInTitle(out, "paused_b"),
            c = frameInTitle(out, "resumed");
  ASSERT_GE(a, 0) << out;
  EXPECT_EQ(a, b) << "Space did not pause: " << out;
  EXPECT_GT(c, b) << "Space did not resume: " << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(quit_ms: (\d+))"))) << out;
  // One short tap is enough: the window closes within a few frames (on llvmpipe with every core
  // busy a frame can take a few hundred ms).
  EXPECT_LT(std::stoi(m[1]), 5000) << "Esc took too long: " << out;
  EXPECT_NE(out.find("rc: 0"), std::string::npos) << out << log;
  EXPECT_NE(log.find("frames captured"), std::string::npos) << log;

  const cv::Mat hud = readXwd(tmp / "hud.xwd"), plain = readXwd(tmp / "nohud.xwd");
  ASSERT_FALSE(hud.empty());
  ASSERT_EQ(hud.size(), plain.size());
  cv::imwrite(std::string(LIVEPROBE_TEST_OUTPUT) + "/window_hud.png",
              hud(cv::Rect(0, 0, 960, 540)));
  const cv::Rect status(12, 12, 200, 150);
  EXPECT_GT(meanAbsDiff(hud(status), plain(status)), 10) << "the HUD region is empty";
  double lo, hi;
  cv::minMaxLoc(hud(status).reshape(1), &lo, &hi);
  EXPECT_GT(hi - lo, 100) << "the HUD region has no text";

  // One press is one exposure step, whichever key types it: '=', '+' (shifted '=') and keypad '+'
  // each brighten the paused frame by the same half stop.
  const cv::Rect window(0, 0, 960, 540);
  const cv::Mat equal = readXwd(tmp / "exposure_equal.xwd"),
                plus = readXwd(tmp / "exposure_plus.xwd"),
                keypad = readXwd(tmp / "exposure_KP_Add.xwd");
  ASSERT_FALSE(equal.empty() || plus.empty() || keypad.empty());
  const double base = cv::mean(plain(window))[1], brighter = cv::mean(equal(window))[1];
  EXPECT_GT(brighter, base + 2) << "'=' did not raise the exposure";
  EXPECT_LT(meanAbsDiff(plus(window), equal(window)), 0.5) << "'+' is not one step";
  EXPECT_LT(meanAbsDiff(keypad(window), equal(window)), 0.5) << "keypad '+' is not one step";
}

// A window on llvmpipe keeps its rate by itself: the bundled 30 frames/s recording on the bunny
// with the sun and ground, at 1280x720, for 8 s each way. With dynamic resolution it draws at
// least 1.5 times the frames it draws at full resolution with MSAA (a ratio within one run, so a
// busy machine slows both), and the summary says at what scale it ended.
TEST(Window, DynamicResolutionKeepsTheRate) {
  const std::string xvfb = lpt::xvfbRun("1280x720x24");
  const std::string cmd = xvfb + LIVEPROBE_BIN + " replay " + LIVEPROBE_SOURCE_DIR +
                          "/recordings/sky.mkv --sun --ground --model " +
                          lpt::dataPath("models/stanford-bunny.obj") +
                          " --size 1280x720 --loop --duration 8";
  auto drawn = [](const std::string& out) {
    std::smatch m;
    return std::regex_search(out, m, std::regex(R"((\d+) frames captured, (\d+) drawn)"))
               ? std::stoi(m[2])
               : -1;
  };
  const auto dynamic = lpt::runCommand(cmd);
  ASSERT_EQ(dynamic.exitCode, 0) << dynamic.output;
  const auto full = lpt::runCommand(cmd + " --full-resolution");
  ASSERT_EQ(full.exitCode, 0) << full.output;
  EXPECT_NE(dynamic.output.find("software GL: 3D view at"), std::string::npos) << dynamic.output;
  EXPECT_EQ(full.output.find("software GL: 3D view at"), std::string::npos) << full.output;
  const int a = drawn(dynamic.output), b = drawn(full.output);
  ASSERT_GT(b, 0) << full.output;
  std::printf("drawn in 10 s: %d with dynamic resolution, %d at full resolution\n", a, b);
  EXPECT_GE(a, 3 * b / 2) << dynamic.output << full.output;
}

// A replay in a window says at its start when the window will close: after the file's frames
// (or --frames), unless --loop plays on.
TEST(Window, ReplaySaysWhenTheWindowCloses) {
  const std::string xvfb = lpt::xvfbRun("640x480x24");
  const std::string seq = std::string(LIVEPROBE_SOURCE_DIR) + "/recordings/sky-hdr";
  const auto run = lpt::runCommand(xvfb + LIVEPROBE_BIN + " replay " + seq +
                                   " --size 160x90 --msaa 1 --no-hud --frames 5");
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("the window closes after 5 frames of image sequence"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("--loop plays on"), std::string::npos) << run.output;
}

// A stream in a window projected on the GPU: the capture thread's EGL context beside the
// window's (sharing its objects, on the window's EGL display; one process, GL's functions loaded
// once for both), the CPU's coefficients frame by frame, said in the summary.
TEST(Window, ReplayProjectsOnTheGpuBesideTheWindow) {
  const std::string xvfb = lpt::xvfbRun("640x480x24");
  const std::string seq = std::string(LIVEPROBE_SOURCE_DIR) + "/recordings/sky-hdr";
  std::vector<std::vector<nlohmann::json>> records;
  for (const std::string on : {"gpu", "cpu"}) {
    const std::string file = std::string(LIVEPROBE_TEST_OUTPUT) + "/window-" + on + ".jsonl";
    const auto run = lpt::runCommand(xvfb + LIVEPROBE_BIN + " replay " + seq +
                                     " --size 160x90 --msaa 1 --no-hud --frames 5 --projection " +
                                     on + " --coeffs-out " + file);
    ASSERT_EQ(run.exitCode, 0) << run.output;
    EXPECT_NE(run.output.find(on == "gpu" ? "projected on the GPU, EGL" : "projected on the CPU"),
              std::string::npos)
        << run.output;
    std::ifstream in(file);
    records.emplace_back();
    for (std::string line; std::getline(in, line);)
      records.back().push_back(nlohmann::json::parse(line));
  }
  ASSERT_EQ(records[0].size(), 5u);
  ASSERT_EQ(records[1].size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) {
    const auto& a = records[0][i]["coefficients"];
    const auto& b = records[1][i]["coefficients"];
    const double l00 = b["L00"][1].get<double>();
    for (const auto& [name, value] : b.items())
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(a[name][c].get<double>(), value[c].get<double>(), 1e-5 * l00) << i << name;
  }
}

// A display without EGL (EGL's vendor library pointing nowhere): the window's context is GLX's,
// the stream plays in it on the CPU, and --projection gpu is refused in one line.
TEST(Window, WithoutEglTheWindowIsGlx) {
  const std::string run = lpt::xvfbRun("640x480x24") +
                          "env __EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json " + LIVEPROBE_BIN +
                          " replay " + LIVEPROBE_SOURCE_DIR +
                          "/recordings/sky-hdr --size 160x90 --msaa 1 --no-hud --frames 3";
  const auto cpu = lpt::runCommand(run);
  ASSERT_EQ(cpu.exitCode, 0) << cpu.output;
  EXPECT_NE(cpu.output.find("the window closes after 3 frames"), std::string::npos) << cpu.output;
  EXPECT_EQ(cpu.output.find("drawing headless"), std::string::npos) << cpu.output;
  EXPECT_NE(cpu.output.find("projected on the CPU"), std::string::npos) << cpu.output;
  const auto gpu = lpt::runCommand(run + " --projection gpu");
  EXPECT_EQ(gpu.exitCode, 1) << gpu.output;
  EXPECT_EQ(lpt::lineCount(gpu.output), 1) << gpu.output;
  EXPECT_NE(gpu.output.find("--projection gpu: cannot open EGL"), std::string::npos) << gpu.output;
}

// The coefficient editor saves with Ctrl+S (in a real window) what `render --coeffs` reads.
TEST(Window, ViewSavesTheCoefficientsForRender) {
  lpt::TempDir tmp;
  const std::string out = tmp / "edited.json";
  const auto run = lpt::runCommand(lpt::xvfbRun("1024x768x24") + std::string(LIVEPROBE_SOURCE_DIR) +
                                   "/tests/scripts/view_save.sh " + LIVEPROBE_BIN + " " + out +
                                   " --coeff L00=0.5 --coeff L10=0.2,0.1,0");
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("rc: 0"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("saved the coefficients to"), std::string::npos) << run.output;
  const auto j = nlohmann::json::parse(std::ifstream(out))["coefficients"];
  for (const auto name : lp::kShNames)
    for (int ch = 0; ch < 3; ++ch) {
      const double want = name == "L00"   ? 0.5
                          : name == "L10" ? std::array{0.2, 0.1, 0.0}[std::size_t(ch)]
                                          : 0.0;
      EXPECT_NEAR(j[std::string(name)][ch].get<double>(), want, 1e-6) << name;
    }
  const auto r =
      runLiveprobe("render --headless --size 64x64 --coeffs " + out + " --out " + tmp / "r.png");
  EXPECT_EQ(r.exitCode, 0) << r.output;
}

}  // namespace
