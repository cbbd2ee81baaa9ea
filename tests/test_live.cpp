// liveprobe live against the emulated camera (tests/v4l2emu, LD_PRELOAD): the real V4L2 code
// path through open/ioctl/mmap/poll, in every format, and every fault. Always runs; no skip.
#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <regex>
#include <set>

#include "emulator.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/sh/sh.h"
#include "sky_frames.h"
#include "test_util.h"

namespace {

namespace fs = std::filesystem;
using lpt::Emulator;
using lpt::readJsonl;
constexpr int kFrames = 10;

const std::string kCommon = " --headless --view-size 64x36 --no-background ";
const std::string kReplay = " --headless --size 64x36 --no-background ";

// A full session per format: the coefficients of every frame equal those of the same frames read
// from the files by the replay pipeline, once divided by the camera's exposure time (live
// coefficients are radiance per second; the emulated camera's auto exposure settles at 33.3 ms).
// MJPEG frames are the files' own JPEG bytes, so they agree to float rounding; YUYV and NV12 carry
// the frames through 4:2:2 / 4:2:0 chroma and 8-bit YUV, which moves a coefficient by at most ~0.5%
// of L00 (tolerance 1%).
TEST(Live, FullSessionInEveryFormat) {
  Emulator emu({"MJPG_640x320", "YUYV_640x320", "YUYV_320x160", "NV12_640x320"});
  const std::vector<std::tuple<std::string, std::string, double>> cases = {
      {"mjpeg", "640x320", 1e-5},
      {"yuyv", "640x320", 0.01},
      {"yuyv", "320x160", 0.01},
      {"nv12", "640x320", 0.01}};
  for (const auto& [fmt, size, tol] : cases) {
    const std::string live = emu.tmp / ("live_" + fmt + size + ".jsonl"),
                      ref = emu.tmp / ("ref_" + fmt + size + ".jsonl");
    auto r = emu.run("live /dev/video7 --pixel-format " + fmt + " --size " + size + " --frames " +
                     std::to_string(kFrames) + kCommon + "--coeffs-out " + live);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::string folder = fmt == "mjpeg" ? "MJPG_" : fmt == "yuyv" ? "YUYV_" : "NV12_";
    r = lpt::runLiveprobe("replay " + (emu.tmp.path / "modes" / (folder + size)).string() +
                          kReplay + "--coeffs-out " + ref);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto a = readJsonl(live), b = readJsonl(ref);
    ASSERT_EQ(a.size(), std::size_t(kFrames)) << fmt << " " << size;
    ASSERT_EQ(b.size(), std::size_t(kFrames));
    double worst = 0;
    for (int i = 0; i < kFrames; ++i)
      for (int k = 0; k < 9; ++k)
        for (int c = 0; c < 3; ++c) {
          const std::string n(lp::kShNames[k]);
          const double exposureSeconds = 333e-4;
          const double x = a[i]["coefficients"][n][c].get<double>() * exposureSeconds;
          const double y = b[i]["coefficients"][n][c], l00 = b[i]["coefficients"]["L00"][c];
          worst = std::max(worst, std::abs(x - y) / l00);
        }
    EXPECT_LT(worst, tol) << fmt << " " << size;
    std::cout << fmt << " " << size << ": worst |live - replay| / L00 = " << worst << "\n";
  }
  emu.expectNoLeak();
}

// Per-frame metadata: with auto exposure running (the emulator's exposure_walk changes the
// exposure every frame), each frame is scaled by its own exposure time, the recording keeps every
// frame's exposure, and replaying it gives the live coefficients frame by frame.
TEST(LiveMetadata, EveryFrameKeepsItsOwnExposure) {
  Emulator emu({"MJPG_320x160"}, "exposure_walk");
  const std::string live = emu.tmp / "live.jsonl", rep = emu.tmp / "replay.jsonl",
                    rec = emu.tmp / "rec.mkv";
  auto r = emu.run("live /dev/video7 --frames 12" + kCommon + "--record " + rec + " --coeffs-out " +
                   live);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  nlohmann::json side = nlohmann::json::parse(std::ifstream(rec + ".json"));
  std::set<long> seen;
  for (const auto& e : side["exposures"]) {
    const long units = std::lround(e.get<double>() * 1e4);  // seconds -> the control's 100 us
    EXPECT_TRUE(units >= 200 && units <= 440 && units % 40 == 0)
        << "not an exposure the camera had: " << e;
    seen.insert(units);
  }
  EXPECT_GE(seen.size(), 3u) << "the exposure did not change from frame to frame: " << side.dump();
  r = lpt::runLiveprobe("replay " + rec + kReplay + "--coeffs-out " + rep);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto a = readJsonl(live), b = readJsonl(rep);
  ASSERT_EQ(a.size(), 12u);
  ASSERT_EQ(b.size(), a.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double x = a[i]["coefficients"]["L00"][c], y = b[i]["coefficients"]["L00"][c];
      EXPECT_NEAR(y, x, 1e-4 * x) << "frame " << i;  // FFV1 keeps the decoded frames exactly
    }
}

// Glass-to-light latency starts at the driver's capture timestamp: a camera whose frames are
// 200 ms old when dequeued (the emulator's latency=200) shows every figure 200 ms later, in
// --coeffs-out (capture to coefficients) and in the summary (capture to shown).
TEST(LiveMetadata, LatencyStartsAtTheCaptureTimestamp) {
  auto medianLatency = [](const std::string& faults, std::string& summary) {
    Emulator emu({"MJPG_320x160"}, faults);
    const std::string out = emu.tmp / "c.jsonl";
    const auto r = emu.run("live /dev/video7 --frames 12" + kCommon + "--coeffs-out " + out);
    EXPECT_EQ(r.exitCode, 0) << r.output;
    summary = r.output;
    std::vector<double> v;
    for (const auto& j : readJsonl(out)) v.push_back(j["latency_ms"]["coefficients"].get<double>());
    EXPECT_EQ(v.size(), 12u);
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  std::string fast, slow;
  const double a = medianLatency("", fast), b = medianLatency("latency=200", slow);
  EXPECT_GE(a, 0.0);
  EXPECT_LT(a, 150.0);  // decode and projection of a 320x160 frame
  EXPECT_NEAR(b - a, 200.0, 40.0) << a << " then " << b;
  for (const auto* s : {&fast, &slow})
    EXPECT_NE(s->find("latency ms (capture to shown): p50"), std::string::npos) << *s;
}

/// Runs live against `emu`, expecting one line saying `says` and exit 1 within `maxSeconds`;
/// returns how long the run took.
double expectFault(const Emulator& emu, const std::string& args, const std::string& says,
                   double maxSeconds = 5) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = emu.run("live /dev/video7" + kCommon + args);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.exitCode, 1) << r.output;
  // The error is one line; before it at most the camera's description and "recorded N frames".
  EXPECT_LE(lpt::lineCount(r.output), 3) << r.output;
  const std::string last = r.output.substr(r.output.rfind('\n', r.output.size() - 2) + 1);
  EXPECT_NE(last.find(says), std::string::npos)
      << "the last line should say what went wrong: " << r.output;
  EXPECT_NE(r.output.find("/dev/video7"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(says), std::string::npos) << r.output;
  EXPECT_LT(s, maxSeconds) << "took too long: " << r.output;
  return s;
}

TEST(LiveFaults, UnsupportedFormat) {
  Emulator only({"MJPG_320x160"});
  expectFault(only, "--pixel-format nv12", "does not offer NV12");
  Emulator refuses({"MJPG_320x160"}, "einval_fmt");
  expectFault(refuses, "--pixel-format mjpeg", "VIDIOC_S_FMT MJPG: Invalid argument");
  refuses.expectNoLeak();
}

TEST(LiveFaults, BusyDevice) {
  Emulator atOpen({"MJPG_320x160"}, "busy_open");
  expectFault(atOpen, "", "busy");
  Emulator atReqbufs({"MJPG_320x160"}, "busy_reqbufs");
  expectFault(atReqbufs, "", "device busy");
  atReqbufs.expectNoLeak();
}

// A node the user may not open (not in the video group): the line says what to do.
TEST(LiveFaults, PermissionDenied) {
  Emulator emu({"MJPG_320x160"}, "denied_open");
  expectFault(emu, "", "open: permission denied (camera nodes belong to the video group");
  expectFault(emu, "", "sudo usermod -aG video $USER");
}

// A camera that sends fewer frames than its mode says (auto exposure in dim light): the run goes
// on, and its end says the rate the driver's timestamps show and what keeps the mode's. The
// emulated camera paces 6 frames a second in a 30 frames/s mode; a loaded machine can only make
// it slower.
TEST(LiveHints, ACameraSlowerThanItsModeIsSaid) {
  Emulator emu({"MJPG_320x160"}, "slow_fps=6");
  const auto r = emu.run("live /dev/video7 --frames 20" + kCommon);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m,
                                std::regex(R"(hint: the camera sent ([0-9.]+) frames/s, not the )"
                                           R"(30 fps of its mode: .*--lock-exposure)")))
      << r.output;
  EXPECT_GT(std::stod(m[1]), 2.0) << r.output;
  EXPECT_LT(std::stod(m[1]), 6.5) << r.output;
}

TEST(LiveFaults, FewerBuffersGranted) {
  Emulator two({"MJPG_320x160"}, "grant=2");
  expectFault(two, "", "granted 2 buffers, need at least 3");
  EXPECT_NE(two.logText().find("REQBUFS 0"), std::string::npos) << "no rollback: " << two.logText();
  two.expectNoLeak();
  Emulator three({"MJPG_320x160"}, "grant=3");  // fewer than asked, enough to run
  const auto r = three.run("live /dev/video7 --frames 5" + kCommon);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  three.expectNoLeak();
}

// The stall is noticed after --timeout: a run with a timeout 7.5 s longer takes about that much
// longer. The two runs are measured in turn, so a loaded machine slows both alike; the margin
// takes a slow start's seconds.
TEST(LiveFaults, CameraStopsSending) {
  Emulator emu({"MJPG_320x160"}, "stop_after=4");
  const double quick = expectFault(emu, "--timeout 0.5", "the camera stopped sending", 60);
  const double slow = expectFault(emu, "--timeout 8", "the camera stopped sending", 60);
  EXPECT_GT(slow - quick, 4.0) << "--timeout 0.5 took " << quick << " s, --timeout 8 " << slow;
  emu.expectNoLeak();
}

TEST(LiveFaults, SignalsInterruptPollAndDequeue) {
  Emulator emu({"MJPG_320x160"}, "eintr");
  const std::string out = emu.tmp / "c.jsonl";
  const auto r = emu.run("live /dev/video7 --frames 20" + kCommon + "--coeffs-out " + out);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(readJsonl(out).size(), 20u);
  emu.expectNoLeak();
}

// Unplugged mid-stream: a clear error, and the recording is finalised and plays to the last frame.
TEST(LiveFaults, UnpluggedMidStreamWithRecording) {
  Emulator emu({"MJPG_320x160"}, "unplug_after=8");
  const std::string rec = emu.tmp / "rec.mkv", out = emu.tmp / "c.jsonl";
  expectFault(emu, "--record " + rec + " --coeffs-out " + out, "unplugged");
  ASSERT_TRUE(fs::exists(rec)) << "the recording was not finalised";
  cv::VideoCapture cap(rec);
  int n = 0;
  for (cv::Mat m; cap.read(m);) ++n;
  EXPECT_EQ(n, 8);
  EXPECT_EQ(readJsonl(out).size(), 8u);
  const auto r = lpt::runLiveprobe("replay " + rec + kReplay);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  emu.expectNoLeak(true);
}

// Soak: a long live session from a camera that misbehaves every few hundred frames: a frame the
// driver flags as damaged, a frame of garbage it does not flag, a frame lost before the reader,
// and EINTR on poll and dequeue. Memory, descriptors and threads stay flat (tests/scripts/soak.sh
// samples them), every fault is counted as a skipped frame, and the session ends normally. The
// short run is 2000 frames; LIVEPROBE_SOAK_FRAMES=20000 runs the long one.
TEST(LiveSoak, FaultsEveryFewHundredFrames) {
  const char* n = std::getenv("LIVEPROBE_SOAK_FRAMES");
  const int frames = n ? std::atoi(n) : 2000;
  Emulator emu({"MJPG_320x160"}, "corrupt_every=300,garbage_every=450,gap_every=500,eintr");
  const std::string env =
      "LIVEPROBE_PRELOAD=" + std::string(LIVEPROBE_EMU) +
      " LPEMU_DEVICE=/dev/video7 LPEMU_FPS=400 LPEMU_SOURCE=" + (emu.tmp.path / "modes").string() +
      " LPEMU_LOG=" + emu.log() + " LPEMU_FAULTS=" + emu.faults + " ";
  const auto r = lpt::runCommand(env + LIVEPROBE_SOURCE_DIR + "/tests/scripts/soak.sh " +
                                 LIVEPROBE_BIN + " " + std::to_string(frames) + " /dev/video7");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  // Each fault is one frame liveprobe never shows: captured + faults = frames served.
  const auto skippedAt = r.output.find(" skipped (corrupt)");
  ASSERT_NE(skippedAt, std::string::npos) << r.output;
  const std::size_t start = r.output.rfind(", ", skippedAt) + 2;
  const long skipped = std::stol(r.output.substr(start, skippedAt - start));
  const long expected = frames / 300 + frames / 450 + frames / 500;
  EXPECT_GE(skipped, expected * 9 / 10) << r.output;
  EXPECT_LE(skipped, expected * 11 / 10 + 2) << r.output;
  emu.expectNoLeak();
}

// A camera that refuses a control: --lock-exposure fails with one line naming the control and
// the value, and never reports a lock it did not get.
TEST(LiveFaults, RefusedControlIsAnError) {
  Emulator emu({"MJPG_320x160"}, "refuse=" + std::to_string(V4L2_CID_GAIN));
  expectFault(emu, "--lock-exposure 0.3 --frames 3",
              "VIDIOC_S_CTRL Gain = 96: Device or resource busy");
  const auto r = emu.run("live /dev/video7 --lock-exposure 0.3 --frames 3" + kCommon);
  EXPECT_EQ(r.output.find("locked"), std::string::npos)
      << "reported a lock it did not get: " << r.output;
  emu.expectNoLeak();
}

// --lock-exposure: auto modes on, settle, read, auto modes off, manual values written back; the
// emulator refuses manual values while an auto mode is on, so the order is checked by what stuck.
TEST(Live, LockExposureOrder) {
  Emulator emu({"MJPG_320x160"});
  const auto r = emu.run("live /dev/video7 --lock-exposure 0.3 --frames 5" + kCommon);
  // Without a value the option is a flag (2 s of settling).
  const auto flag = emu.run("live /dev/video7 --frames 2" + kCommon + "--lock-exposure");
  EXPECT_EQ(flag.exitCode, 0) << flag.output;
  EXPECT_NE(flag.output.find("locked after 2.0 s"), std::string::npos) << flag.output;
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("exposure 333 x 100 us, gain 96, white balance 5200 K"),
            std::string::npos)
      << r.output;
  const std::string l = emu.logText();
  const std::vector<std::string> order = {"S_CTRL Auto Exposure 3",
                                          "S_CTRL Gain, Automatic 1",
                                          "S_CTRL White Balance, Automatic 1",
                                          "S_CTRL Auto Exposure 1",
                                          "S_CTRL Exposure Time, Absolute 333\n",
                                          "S_CTRL Gain, Automatic 0",
                                          "S_CTRL Gain 96\n",
                                          "S_CTRL White Balance, Automatic 0",
                                          "S_CTRL White Balance Temperature 5200\n"};
  std::size_t at = 0;
  for (const auto& step : order) {
    const auto p = l.find(step, at);
    ASSERT_NE(p, std::string::npos) << "missing or out of order: " << step << "\n" << l;
    at = p;
  }
  EXPECT_EQ(l.find("refused"), std::string::npos) << l;
}

TEST(Live, DevicesListsFormatsSizesRatesControls) {
  Emulator emu({"MJPG_640x320", "YUYV_320x160"});
  const auto r = emu.run("devices /dev/video7");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  for (const char* s :
       {"liveprobe emulated camera", "MJPG 640x320 @ 30 fps", "YUYV 320x160 @ 30 fps",
        "control Exposure Time, Absolute", "control White Balance Temperature"})
    EXPECT_NE(r.output.find(s), std::string::npos) << s << "\n" << r.output;
}

// A UVC camera has a second node for metadata: it answers QUERYCAP but is not a camera, so
// devices lists the camera and skips the metadata node (saying so when it was named).
TEST(Live, DevicesListsOnlyVideoCaptureNodes) {
  Emulator emu({"MJPG_640x320"});
  const auto r = emu.run("devices /dev/video7 /dev/video8");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("/dev/video7: liveprobe emulated camera"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("/dev/video8: liveprobe emulated camera ("), std::string::npos)
      << "the metadata node was listed as a camera: " << r.output;
  EXPECT_NE(r.output.find(
                "/dev/video8: liveprobe emulated camera: a metadata node, not a camera; skipped"),
            std::string::npos)
      << r.output;
  // live refuses it with one line, as before (QUERYCAP has no video capture).
  const auto l = emu.run("live /dev/video8 --frames 1 --headless");
  EXPECT_EQ(l.exitCode, 1) << l.output;
  EXPECT_EQ(lpt::lineCount(l.output), 1) << l.output;
  EXPECT_NE(l.output.find("/dev/video8"), std::string::npos) << l.output;
}

// A missing device or a node that is no camera fails at once: one line naming it, the path opened
// once, and no thread sleeps, polls or selects on the way out (strace's record of every thread,
// not a clock: the machine may be busy).
TEST(LiveFaults, MissingDevicesFailFast) {
  lpt::TempDir tmp;
  const std::string trace = (tmp.path / "trace").string();
  for (const std::string dev : {"/dev/video99", "/dev/null"}) {
    // (LeakSanitizer cannot stop the world under ptrace: off for this run in a sanitizer build.)
    const auto r = lpt::runCommand(
        "ASAN_OPTIONS=\"${ASAN_OPTIONS}:detect_leaks=0\" "
        "strace -f -qq -e trace=openat,nanosleep,clock_nanosleep,poll,ppoll,select,pselect6,"
        "epoll_wait,epoll_pwait -o " +
        trace + " " + LIVEPROBE_BIN + " live " + dev + kCommon);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_EQ(lpt::lineCount(r.output), 1) << r.output;
    EXPECT_NE(r.output.find(dev), std::string::npos) << r.output;
    std::ifstream in(trace);
    ASSERT_TRUE(in) << "strace wrote no record: " << r.output;
    int opens = 0, lines = 0;
    for (std::string line; std::getline(in, line); ++lines) {
      if (line.find("\"" + dev + "\"") != std::string::npos) ++opens;
      // "PID call(arguments) = result" (or "PID <... call resumed>"): every call traced but
      // openat is a wait.
      std::smatch call;
      ASSERT_TRUE(std::regex_search(line, call, std::regex(R"(^\d+ +(?:<\.\.\. )?(\w+)[ (])")))
          << line;
      EXPECT_EQ(call[1], "openat") << "a wait on the way out: " << line;
    }
    EXPECT_GT(lines, 0);
    EXPECT_EQ(opens, 1) << dev << " opened " << opens << " times";
  }
}

TEST(LiveCamera, CalibratesALensFromBoardsHeldStill) {
  // recordings/fisheye/boards: 16 photos of a 9x6 board through the tests' fisheye (test_lens's
  // KannalaBrandt, 1280x960; recordings/fisheye/lens.yaml is it at 640x480). The camera shows
  // each for three frames, as a hand holds a board still, and the first again after the second:
  // that place is kept once.
  const fs::path boards = fs::path(LIVEPROBE_SOURCE_DIR) / "recordings/fisheye/boards";
  std::vector<std::string> photos;
  for (const auto& e : fs::directory_iterator(boards)) photos.push_back(e.path().string());
  std::sort(photos.begin(), photos.end());
  ASSERT_EQ(photos.size(), 16u);
  std::vector<std::string> frames;
  for (std::size_t i = 0; i < photos.size(); ++i) {
    for (int r = 0; r < 3; ++r) frames.push_back(photos[i]);
    if (i == 1)
      for (int r = 0; r < 3; ++r) frames.push_back(photos[0]);
  }
  Emulator emu("YUYV_1280x960", frames);
  lpt::TempDir out;
  const std::string file = (out.path / "lens.yaml").string();
  const auto r = emu.run(
      "calibrate-lens --device /dev/video7 --board 9x6 --square 0.03 --boards "
      "16 --out " +
      file);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("16 frames of /dev/video7 keep the 9x6 board still"), std::string::npos)
      << r.output;
  // Kept: the middle frame of each board's three (the first shows it moving in), never one of
  // the first board's second visit (frames 6 to 8).
  std::set<int> kept;
  const std::regex line(R"(board \d+ of 16 kept \(frame (\d+)\))");
  for (auto it = std::sregex_iterator(r.output.begin(), r.output.end(), line);
       it != std::sregex_iterator(); ++it)
    kept.insert(std::stoi((*it)[1]));
  EXPECT_EQ(kept.size(), 16u) << r.output;
  for (int f = 6; f <= 8; ++f) EXPECT_EQ(kept.count(f), 0u) << f << "\n" << r.output;
  // The truth, scaled from 640x480 (OpenCV's pixel centres are whole numbers).
  cv::FileStorage truth(std::string(LIVEPROBE_SOURCE_DIR) + "/recordings/fisheye/lens.yaml",
                        cv::FileStorage::READ);
  cv::Mat K0, K;
  truth["camera_matrix"] >> K0;
  cv::FileStorage got(file, cv::FileStorage::READ);
  got["camera_matrix"] >> K;
  ASSERT_FALSE(K.empty()) << r.output;
  EXPECT_NEAR(K.at<double>(0, 0), 2 * K0.at<double>(0, 0), 0.01 * 2 * K0.at<double>(0, 0));
  EXPECT_NEAR(K.at<double>(1, 1), 2 * K0.at<double>(1, 1), 0.01 * 2 * K0.at<double>(1, 1));
  EXPECT_NEAR(K.at<double>(0, 2), 2 * K0.at<double>(0, 2) + 0.5, 2.0);
  EXPECT_NEAR(K.at<double>(1, 2), 2 * K0.at<double>(1, 2) + 0.5, 2.0);
}

}  // namespace
