// liveprobe replay and record end to end: real video checked frame by frame against an
// independent float64 computation, corrupt and truncated files, outputs.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <random>
#include <regex>
#include <thread>

#include "liveprobe/capture/open_source.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/sh/projector.h"
#include "liveprobe/sh/sh.h"
#include "test_util.h"

namespace {

using lpt::expectOneLineError;
using lpt::runLiveprobe;
constexpr double kPi = std::numbers::pi;

std::vector<nlohmann::json> readJsonl(const std::string& path) {
  std::vector<nlohmann::json> out;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) out.push_back(nlohmann::json::parse(line));
  return out;
}

// The reference: OpenCV decode, sRGB to linear in double, the frame as an equirect of its own
// aspect, the basis at pixel centres times the exact row solid angle, summed in double. Every
// basis function is a function of the row's polar angle times one of 1, sin(phi), cos(phi),
// sin(2 phi), cos(2 phi), so each row is summed once against those five and the row's factors
// are applied after (the same sum, five multiply-adds a pixel and channel instead of 27).
std::array<double, 27> referenceCoefficients(const cv::Mat& bgr) {
  const int w = bgr.cols, h = bgr.rows;
  double lut[256];
  for (int i = 0; i < 256; ++i) {
    const double v = i / 255.0;
    lut[i] = v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
  }
  std::vector<std::array<double, 5>> az(w);  // 1, sin, cos, sin 2phi, cos 2phi
  for (int j = 0; j < w; ++j) {
    const double p = 2 * kPi * (j + 0.5) / w;
    az[j] = {1, std::sin(p), std::cos(p), std::sin(2 * p), std::cos(2 * p)};
  }
  const double k0 = 0.5 / std::sqrt(kPi), k1 = std::sqrt(3 / (4 * kPi)),
               k4 = std::sqrt(15 / (16 * kPi)), k5 = std::sqrt(15 / (4 * kPi)),
               k6 = std::sqrt(5 / (16 * kPi));
  std::array<double, 27> L{};
  for (int i = 0; i < h; ++i) {
    const double t = kPi * (i + 0.5) / h, ct = std::cos(t), st = std::sin(t);
    const double dw = 2 * kPi / w * (std::cos(kPi * i / h) - std::cos(kPi * (i + 1) / h));
    const auto* row = bgr.ptr<std::uint8_t>(i);
    double s[5][3] = {};
    for (int j = 0; j < w; ++j) {
      const double rgb[3] = {lut[row[3 * j + 2]], lut[row[3 * j + 1]], lut[row[3 * j]]};
      for (int f = 0; f < 5; ++f)
        for (int c = 0; c < 3; ++c) s[f][c] += rgb[c] * az[j][f];
    }
    // Basis k = polar factor times azimuthal function f (order of lp::kShNames).
    const std::pair<double, int> y[9] = {{k0, 0},
                                         {k1 * st, 1},
                                         {k1 * ct, 0},
                                         {k1 * st, 2},
                                         {k4 * st * st, 3},
                                         {k5 * st * ct, 1},
                                         {k6 * (3 * ct * ct - 1), 0},
                                         {k5 * st * ct, 2},
                                         {k4 * st * st, 4}};
    for (int k = 0; k < 9; ++k)
      for (int c = 0; c < 3; ++c) L[3 * k + c] += y[k].first * s[y[k].second][c] * dw;
  }
  return L;
}

// liveprobe replay pano.mp4 --headless --coeffs-out c.jsonl: one line per decoded frame, each
// equal to the float64 reference on that frame within 1e-4 of L00.
TEST(ReplayCli, RealVideoCheckedFrameByFrame) {
  lpt::TempDir tmp;
  const std::string video = lpt::dataPath("video/pano.mp4");
  const std::string out = tmp / "c.jsonl";
  const auto r =
      runLiveprobe("replay " + video + " --headless --coeffs-out " + out + " --size 64x36");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto lines = readJsonl(out);
  cv::VideoCapture cap(video, cv::CAP_FFMPEG);
  std::vector<cv::Mat> frames;
  for (cv::Mat m; cap.read(m);) frames.push_back(m.clone());
  ASSERT_EQ(lines.size(), frames.size());
  EXPECT_EQ(frames.size(), 188u);  // what OpenCV decodes here
  std::vector<std::array<double, 27>> ref(frames.size());
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < 2; ++t)
    pool.emplace_back([&, t] {
      for (std::size_t i = t; i < frames.size(); i += 2) ref[i] = referenceCoefficients(frames[i]);
    });
  for (auto& th : pool) th.join();
  double worst = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto& j = lines[i];
    ASSERT_EQ(j["frame"].get<std::size_t>(), i);
    if (i > 0) {
      EXPECT_GT(j["time"].get<double>(), lines[i - 1]["time"].get<double>());
    }
    for (const char* key : {"grab", "convert", "project", "render"})
      EXPECT_TRUE(j["timings_ms"][key].is_number());
    for (int k = 0; k < 9; ++k)
      for (int c = 0; c < 3; ++c) {
        const double got = j["coefficients"][std::string(lp::kShNames[k])][c].get<double>();
        const double diff = std::abs(got - ref[i][3 * k + c]) / ref[i][c];
        worst = std::max(worst, diff);
        ASSERT_LT(diff, 1e-4) << "frame " << i << " " << lp::kShNames[k] << " ch " << c;
      }
  }
  std::cout << "worst |coefficient - reference| / L00 over " << lines.size() << " frames: " << worst
            << "\n";
}

// A copy of pano.mp4 with garbage written over two stretches in the middle.
std::string corruptCopy(const lpt::TempDir& tmp) {
  std::ifstream in(lpt::dataPath("video/pano.mp4"), std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  std::mt19937 rng(1);
  for (double at : {0.4, 0.6})
    for (std::size_t i = 0; i < 30000; ++i) bytes[std::size_t(at * bytes.size()) + i] = char(rng());
  const std::string f = tmp / "corrupt.mp4";
  std::ofstream(f, std::ios::binary) << bytes;
  return f;
}

TEST(ReplayCliBadInput, CorruptFramesAreSkippedAndCounted) {
  lpt::TempDir tmp;
  const std::string f = corruptCopy(tmp), out = tmp / "c.jsonl";
  const auto r = runLiveprobe("replay " + f + " --headless --size 32x18 --coeffs-out " + out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      r.output, m, std::regex(R"((\d+) frames captured.*, (\d+) skipped \(corrupt\))")))
      << r.output;
  const int captured = std::stoi(m[1]), skipped = std::stoi(m[2]);
  EXPECT_GT(skipped, 0);
  EXPECT_GT(captured, 100);
  EXPECT_EQ(readJsonl(out).size(), std::size_t(captured));
  EXPECT_EQ(r.output.find("[h264"), std::string::npos) << "FFmpeg's own log leaked: " << r.output;
}

TEST(ReplayCliBadInput, TruncatedVideoEndsCleanlyWithTheCount) {
  lpt::TempDir tmp;
  std::ifstream in(lpt::dataPath("video/pano.webm"), std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const std::string f = tmp / "cut.webm", out = tmp / "c.jsonl";
  std::ofstream(f, std::ios::binary) << bytes.substr(0, bytes.size() * 2 / 3);
  const auto r = runLiveprobe("replay " + f + " --headless --size 32x18 --coeffs-out " + out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex(R"(ended after (\d+) frames of (\d+))")))
      << r.output;
  EXPECT_LT(std::stoi(m[1]), std::stoi(m[2]));
  EXPECT_EQ(readJsonl(out).size(), std::size_t(std::stoi(m[1])));
  // An mp4 cut short loses its index (moov at the end): nothing can be read, one clear line.
  std::ifstream in2(lpt::dataPath("video/pano.mp4"), std::ios::binary);
  std::string mp4((std::istreambuf_iterator<char>(in2)), {});
  const std::string g = tmp / "cut.mp4";
  std::ofstream(g, std::ios::binary) << mp4.substr(0, mp4.size() / 2);
  expectOneLineError("replay " + g + " --headless --size 32x18", g, "cannot open as video");
  EXPECT_FALSE(std::filesystem::exists(tmp / "c2.jsonl"));
}

TEST(ReplayCliBadInput, LayoutThatDoesNotFitTheFrame) {
  const std::string v = lpt::dataPath("video/pano.mp4");
  expectOneLineError("replay " + v + " --headless --layout angular --size 32x18", "pano.mp4",
                     "must be square");
  expectOneLineError("replay " + v + " --headless --layout cube --size 32x18", "pano.mp4", "4:3");
  expectOneLineError("replay " + v + " --headless --layout mirrorball", "mirror ball", "--circle");
}

TEST(ReplayCliBadInput, NothingHalfWrittenOnFailure) {
  lpt::TempDir tmp;
  const std::string out = tmp / "c.jsonl";
  const auto r = runLiveprobe("replay " + lpt::dataPath("video/pano.mp4") +
                              " --headless --layout angular --coeffs-out " + out);
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_TRUE(std::filesystem::is_empty(tmp.path)) << "a partial output was left behind";
}

// record, then replay the recording: every frame comes back, with the outputs asked for.
TEST(ReplayCli, RecordThenReplayWithOutputs) {
  lpt::TempDir tmp;
  const std::string rec = tmp / "sky.mkv";
  auto r = runLiveprobe("record synthetic:64x32@30 --frames 15 --out " + rec);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  ASSERT_TRUE(std::filesystem::exists(rec + ".json"));
  const std::string out = tmp / "c.jsonl", dir = tmp / "frames", vid = tmp / "render.avi";
  r = runLiveprobe("replay " + rec + " --headless --size 64x48 --coeffs-out " + out +
                   " --out-dir " + dir);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(readJsonl(out).size(), 15u);
  int pngs = 0;
  for (auto& e : std::filesystem::directory_iterator(dir)) pngs += e.path().extension() == ".png";
  EXPECT_EQ(pngs, 15);
  r = runLiveprobe("replay " + rec + " --headless --size 64x48 --frames 7 --out-video " + vid);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  cv::VideoCapture cap(vid);
  int n = 0;
  for (cv::Mat m; cap.read(m);) ++n;
  EXPECT_EQ(n, 7);
}

TEST(ReplayCli, HdrSequenceRecordingKeepsTheSun) {
  // An 8-bit video clips the synthetic sky's sun (a lower bound of a few percent); a sequence of
  // EXR frames keeps its radiance. The truth is the synthetic source itself, replayed live: the
  // recording's coefficients and light must be its, to the half floats' precision.
  lpt::TempDir tmp;
  const std::string pattern = tmp / "%03d.exr", mkv = tmp / "sky.mkv";
  const std::string src = "synthetic:128x64@10 --frames 4";
  auto r = runLiveprobe("record " + src + " --out " + pattern);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  ASSERT_EQ(runLiveprobe("record " + src + " --out " + mkv).exitCode, 0);
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(tmp.path))
    files += e.path().extension() == ".exr";
  EXPECT_EQ(files, 4);  // 000 .. 003, and no hidden folder of partial frames left
  for (int i = 0; i < 4; ++i)
    EXPECT_TRUE(std::filesystem::exists(tmp / ("00" + std::to_string(i) + ".exr"))) << i;
  const auto replay = [&](const std::string& source, const std::string& name) {
    const std::string out = tmp / name;
    const auto rr = runLiveprobe("replay " + source +
                                 " --fps 10 --headless --size 32x18 --sun "
                                 "--coeffs-out " +
                                 out);
    EXPECT_EQ(rr.exitCode, 0) << rr.output;
    return readJsonl(out);
  };
  const auto truth = replay(src, "truth.jsonl"), exr = replay(pattern, "exr.jsonl"),
             video = replay(mkv, "mkv.jsonl");
  ASSERT_EQ(truth.size(), 4u);
  ASSERT_EQ(exr.size(), 4u);
  ASSERT_EQ(video.size(), 4u);
  for (std::size_t f = 0; f < 4; ++f) {
    const auto& t = truth[f]["coefficients"];
    const double l00 = t["L00"][1].get<double>();
    for (const auto& [name, v] : t.items())
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(exr[f]["coefficients"][name][c].get<double>(), v[c].get<double>(), 2e-3 * l00)
            << "frame " << f << " " << name;
    ASSERT_EQ(truth[f]["lights"].size(), 1u);
    ASSERT_EQ(exr[f]["lights"].size(), 1u) << "frame " << f;
    const auto &tl = truth[f]["lights"][0], el = exr[f]["lights"][0];
    EXPECT_GT(tl["share"].get<double>(), 0.3);
    EXPECT_NEAR(el["share"].get<double>(), tl["share"].get<double>(), 0.01) << "frame " << f;
    EXPECT_FALSE(el["clipped"].get<bool>());
    // The 8-bit recording's sun is clipped and holds a small part of it.
    ASSERT_EQ(video[f]["lights"].size(), 1u) << "frame " << f;
    for (const auto& vl : video[f]["lights"]) {
      EXPECT_TRUE(vl["clipped"].get<bool>());
      EXPECT_LT(vl["share"].get<double>(), 0.5 * tl["share"].get<double>());
    }
  }
  // A shorter recording under the same pattern leaves no frames of the longer one behind.
  r = runLiveprobe("record synthetic:128x64@10 --frames 2 --out " + pattern);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(tmp / "001.exr"));
  EXPECT_FALSE(std::filesystem::exists(tmp / "002.exr"));
}

TEST(ReplayCli, HdrSequenceRecordingRefusesWhatItCannotKeep) {
  lpt::TempDir tmp;
  expectOneLineError("record synthetic:64x32 --frames 2 --out " + (tmp / "sky.exr"), "sky.exr",
                     "need a frame-number pattern");
  expectOneLineError("record synthetic:64x32 --frames 2 --out " + (tmp / "%04d.png"), "%04d.png",
                     "unsupported extension");
  expectOneLineError("record synthetic:64x32 --frames 2 --out " + (tmp / "no/%04d.exr"), "%04d.exr",
                     "no folder");
  EXPECT_TRUE(std::filesystem::is_empty(tmp.path));
}

TEST(ReplayCli, DefaultRecordingPlays) {
  lpt::TempDir tmp;
  const std::string out = tmp / "c.jsonl";
  const auto r = runLiveprobe("replay --headless --frames 10 --size 64x36 --coeffs-out " + out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("recordings/sky.mkv (256x128, 30 fps)"), std::string::npos) << r.output;
  EXPECT_EQ(readJsonl(out).size(), 10u);
}

// A folder of six cube faces is a cube whether or not --layout says so: the coefficients equal the
// core's projection of the assembled cross as a cube (read as one 4:3 equirect image, L00 would
// be a third lower); replay reads it the same way, and a layout that contradicts it is refused.
TEST(ReplayCli, CubeFaceFolderIsReadAsACube) {
  const std::string dir = lpt::dataPath("cube/pisaHDR");
  auto src = lp::openSource(dir);
  lp::Frame f;
  ASSERT_TRUE(src->next(f));
  ASSERT_EQ(f.format, lp::PanoramaFormat::RgbF32);
  const lp::Sh9 truth =
      lp::project(lp::PanoramaView::rgbF32(f.rgb.data(), f.width, f.height, lp::Layout::Cube));
  const auto r = runLiveprobe("coeffs " + dir + " --format json");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["layout"], "cube");
  for (int ch = 0; ch < 3; ++ch)
    EXPECT_NEAR(j["coefficients"]["L00"][ch].get<double>(), truth.c[0][ch], 1e-4 * truth.c[0][ch]);
  lpt::TempDir tmp;
  const auto rp = runLiveprobe("replay " + dir + " --headless --frames 1 --size 64x36 --quiet " +
                               "--coeffs-out " + (tmp / "c.jsonl"));
  ASSERT_EQ(rp.exitCode, 0) << rp.output;
  const auto lines = readJsonl(tmp / "c.jsonl");
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NEAR(lines[0]["coefficients"]["L00"][0].get<double>(), truth.c[0][0],
              1e-4 * truth.c[0][0]);
  expectOneLineError("coeffs " + dir + " --layout equirect", dir, "cube");
}

// A stream of a lens's frames is the lens as calibrated at its own size, said to be the lens
// scaled at twice it (the same aspect), whatever backdrop the display draws.
TEST(ReplayCli, AStreamOfAScaledLensSaysSo) {
  const std::string dir = std::string(LIVEPROBE_SOURCE_DIR) + "/recordings/fisheye/";
  const auto own =
      runLiveprobe("replay " + dir + "sky.exr --lens " + dir + "lens.yaml --headless --frames 2");
  EXPECT_EQ(own.exitCode, 0) << own.output;
  EXPECT_EQ(own.output.find("scaled"), std::string::npos) << own.output;
  lpt::TempDir tmp;
  cv::Mat frame = cv::imread(dir + "sky.exr", cv::IMREAD_UNCHANGED), twice;
  ASSERT_FALSE(frame.empty());
  cv::resize(frame, twice, cv::Size(), 2.0, 2.0, cv::INTER_LINEAR);
  ASSERT_TRUE(cv::imwrite(tmp / "twice.exr", twice));
  for (const std::string more : {"", " --no-background"}) {
    const auto r = runLiveprobe("replay " + tmp / "twice.exr" + " --lens " + dir +
                                "lens.yaml --headless --frames 2" + more);
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("scaled to this 1280x960 frame"), std::string::npos) << r.output;
  }
}

TEST(ReplayCli, EveryLayoutOption) {
  // coeffs accepts every layout; six cube faces as a folder.
  const auto r =
      runLiveprobe("coeffs " + lpt::dataPath("cube/pisaHDR") + " --layout cube --format text");
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("L22"), std::string::npos);
}

}  // namespace
