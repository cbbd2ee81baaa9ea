// liveprobe live reading H.264 and HEVC from the emulated camera (tests/v4l2emu, LD_PRELOAD),
// whose H264_ and HEVC_ modes encode the sky frames with libx264 and libx265 as a camera's
// encoder does (a key frame every LPEMU_GOP frames, no B-frames, one access unit per buffer).
// The truth is the files themselves, replayed; the loss policy is checked against the fault
// schedule worked out here from the emulator's own log.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "emulator.h"
#include "liveprobe/backends.h"
#include "liveprobe/sh/sh.h"
#include "test_util.h"

#if LIVEPROBE_WITH_NETWORK  // FFmpeg: liveprobe's decoder, and the emulator's encoder
namespace {

using lpt::Emulator;
using lpt::readJsonl;

const std::string kCommon = " --headless --view-size 64x36 --no-background ";
constexpr double kExposureSeconds = 333e-4;  // the emulated camera's settled auto exposure
constexpr int kFiles = 10;                   // lpt::makeModes' frames per mode

/// The coefficients of the mode's files in name order, as 4:2:0 video carries them: encoded
/// losslessly by FFmpeg's own command (libx264 at QP 0, yuv420p) and replayed. (4:2:0 chroma
/// alone moves these small skies, a sun of a few pixels, by ~3% of L00 from the PNGs: a cost of
/// any 4:2:0 camera, measured against this reference rather than counted as the decoder's.)
std::vector<nlohmann::json> replayed(const Emulator& emu, const std::string& mode) {
  const std::string video = emu.tmp / (mode + ".mkv"), out = emu.tmp / ("ref_" + mode + ".jsonl");
  auto r = lpt::runCommand("ffmpeg -nostdin -v error -y -framerate 30 -i " +
                           (emu.tmp.path / "modes" / mode / "%04d.png").string() +
                           " -c:v libx264 -qp 0 -pix_fmt yuv420p " + video);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  r = lpt::runLiveprobe("replay " + video +
                        " --headless --size 64x36 --no-background --coeffs-out " + out);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  return readJsonl(out);
}

/// The largest |live x exposure - file| / L00 over every coefficient of a live record against
/// the file it was made from.
double worstOff(const nlohmann::json& live, const nlohmann::json& file) {
  double worst = 0;
  for (int k = 0; k < 9; ++k)
    for (int c = 0; c < 3; ++c) {
      const std::string n(lp::kShNames[k]);
      const double x = live["coefficients"][n][c].get<double>() * kExposureSeconds;
      const double y = file["coefficients"][n][c], l00 = file["coefficients"]["L00"][c];
      worst = std::max(worst, std::abs(x - y) / l00);
    }
  return worst;
}

// Every frame of an H.264 and an HEVC camera gives the coefficients of the file it was encoded
// from, as lossless 4:2:0 video of the file gives them, within 2% of L00: the emulated camera
// converts to 4:2:0 as OpenCV does, FFmpeg's command as swscale does (1.3% apart here, measured
// with the camera encoding losslessly too), and its encoder's CRF 18 adds 0.2%. A frame shown in
// another's place is off by 11% or more (consecutive files differ so). Frames are numbered by the
// driver without a gap.
TEST(LiveH264, EveryFrameIsItsFileWithinTheCompression) {
  Emulator emu({"H264_320x160", "HEVC_320x160"});
  for (const std::string fmt : {"h264", "hevc"}) {
    const std::string mode = (fmt == "h264" ? "H264" : "HEVC") + std::string("_320x160");
    const std::string live = emu.tmp / ("live_" + fmt + ".jsonl");
    const auto r = emu.run("live /dev/video7 --pixel-format " + fmt + " --frames 12" + kCommon +
                           "--coeffs-out " + live);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find(fmt == "h264" ? "H264 320x160" : "HEVC 320x160"), std::string::npos)
        << r.output;
    const auto a = readJsonl(live), files = replayed(emu, mode);
    ASSERT_EQ(a.size(), 12u) << r.output;
    ASSERT_EQ(files.size(), std::size_t(kFiles));
    double worst = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const long seq = a[i]["sequence"].get<long>();
      EXPECT_EQ(seq, long(i)) << fmt << ": frames come one per buffer, in order";
      worst = std::max(worst, worstOff(a[i], files[std::size_t(seq % kFiles)]));
      EXPECT_GE(a[i]["latency_ms"]["coefficients"].get<double>(), 0.0);
    }
    EXPECT_LT(worst, 0.02) << fmt;
    std::cout << fmt << ": worst |live - file| / L00 = " << worst << "\n";
  }
  emu.expectNoLeak();
}

// Frames lost on the way (a sequence gap: lost before the reader; a buffer the driver flags; a
// buffer of garbage it does not) leave the frames after them without their reference: none of
// those is shown until the next key frame, and every other frame is, each the file it was encoded
// from. The schedule is worked out from the emulator's log: its Nth "frame S" line is the Nth
// buffer served with sequence S; a key frame starts every GOP sequence numbers (the encoder made
// one frame per sequence number, lost ones included).
TEST(LiveH264, AFrameLostHidesTheFramesUntilTheNextKeyFrame) {
  constexpr int kGop = 10, kGapEvery = 13, kCorruptEvery = 17, kGarbageEvery = 19, kFrames = 40;
  Emulator emu({"H264_320x160"}, "gap_every=" + std::to_string(kGapEvery) +
                                     ",corrupt_every=" + std::to_string(kCorruptEvery) +
                                     ",garbage_every=" + std::to_string(kGarbageEvery));
  emu.env = "LPEMU_GOP=" + std::to_string(kGop) + " LPEMU_FPS=60 ";
  const std::string live = emu.tmp / "live.jsonl";
  const auto r = emu.run("live /dev/video7 --pixel-format h264 --frames " +
                         std::to_string(kFrames) + kCommon + "--coeffs-out " + live);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  // What was served, and what was lost.
  std::vector<long> served;
  std::istringstream log(emu.logText());
  for (std::string line; std::getline(log, line);)
    if (line.rfind("frame ", 0) == 0) served.push_back(std::stol(line.substr(6)));
  std::set<long> lost;
  for (std::size_t k = 0; k < served.size(); ++k) {
    const long s = served[k];
    if (k > 0)
      for (long g = served[k - 1] + 1; g < s; ++g) lost.insert(g);  // never delivered
    if (s % kCorruptEvery == 0 || (k + 1) % kGarbageEvery == 0) lost.insert(s);
  }
  auto hidden = [&](long s) {  // a loss since the last key frame at or before s
    for (long q = s; q >= 0; --q) {
      if (lost.count(q)) return true;
      if (q % kGop == 0) return false;
    }
    return false;
  };
  const auto a = readJsonl(live);
  ASSERT_EQ(a.size(), std::size_t(kFrames)) << r.output;
  const auto files = replayed(emu, "H264_320x160");
  ASSERT_EQ(files.size(), std::size_t(kFiles));
  std::vector<long> shown;
  for (const auto& rec : a) {
    const long seq = rec["sequence"].get<long>();
    EXPECT_TRUE(shown.empty() || seq > shown.back()) << "out of order: " << seq;
    shown.push_back(seq);
    EXPECT_FALSE(lost.count(seq) || hidden(seq)) << "frame " << seq << " shown; lost: " << r.output;
    EXPECT_LT(worstOff(rec, files[std::size_t(seq % kFiles)]), 0.02) << "frame " << seq;
  }
  // Every other frame up to the last one shown was shown, unless the display took a newer one
  // first (dropped as stale: a busy machine); every lost or hidden one is counted as skipped.
  const auto count = [&](const char* what) {
    const auto at = r.output.find(what);
    EXPECT_NE(at, std::string::npos) << r.output;
    const auto from = r.output.rfind(", ", at) + 2;
    return at == std::string::npos ? -1L : std::stol(r.output.substr(from, at - from));
  };
  long missing = 0, notShown = 0;
  for (long s = 0; s <= shown.back(); ++s) {
    const bool isShown = std::find(shown.begin(), shown.end(), s) != shown.end();
    if (lost.count(s) || hidden(s))
      ++notShown;
    else if (!isShown)
      ++missing;
  }
  EXPECT_GE(notShown, 4) << "the faults did not happen: " << emu.logText();
  EXPECT_LE(missing, count(" dropped (stale)")) << r.output;
  // (Frames after the last one shown may have been read, and skipped, before the run stopped.)
  const long after = served.back() - shown.back();
  EXPECT_GE(count(" skipped (corrupt)"), notShown) << r.output;
  EXPECT_LE(count(" skipped (corrupt)"), notShown + after) << after << "\n" << r.output;
  emu.expectNoLeak();
}

}  // namespace
#endif
