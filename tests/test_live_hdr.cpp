// Exposure bracketing end to end: liveprobe live --bracket against the emulated camera rendering
// the synthetic sky's HDR frames (recordings/sky-hdr) as an 8-bit sensor would, with a late and
// rounding exposure control and per-frame exposure metadata. The truth is the HDR replay of the
// same source frames, divided by the camera's gain (the emulator's sensitivity is 1).
#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "emulator.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/hdr/calibrate.h"
#include "liveprobe/hdr/merge.h"
#include "test_util.h"
#include "turned_map.h"

namespace {

namespace fs = std::filesystem;
using lpt::Emulator;
using lpt::readJsonl;
using nlohmann::json;

std::string skyFrame(int i) {
  char name[64];
  std::snprintf(name, sizeof name, "/recordings/sky-hdr/%04d.exr", i);
  return std::string(LIVEPROBE_SOURCE_DIR) + name;
}

const std::string kBracket =
    " --bracket -12,-6,0 --lock-exposure 0.3 --headless --view-size 64x36 --no-background ";

// The camera's gain over its unit gain (64), from "locked after ...: ... gain N": the emulated
// sensor multiplies radiance by it.
double gainOf(const std::string& output) {
  std::smatch m;
  EXPECT_TRUE(std::regex_search(output, m, std::regex("gain ([0-9]+)"))) << output;
  return m.empty() ? 1.0 : std::stod(m[1]) / 64.0;
}

double angleDeg(const json& a, const json& b) {
  double d = 0;
  for (int i = 0; i < 3; ++i) d += a[i].get<double>() * b[i].get<double>();
  return std::acos(std::clamp(d, -1.0, 1.0)) * 180.0 / M_PI;
}

// The largest difference of the 27 numbers, in units of the truth's green L00, after dividing
// `measured` by `scale`.
double worstCoefficient(const json& measured, const json& truth, double scale) {
  double worst = 0;
  for (const auto& [name, rgb] : truth.items())
    for (int c = 0; c < 3; ++c)
      worst =
          std::max(worst, std::abs(measured[name][c].get<double>() / scale - rgb[c].get<double>()));
  return worst / truth["L00"][1].get<double>();
}

// A bracketed live run (-12,-6,0) of the still sky in `mode` with the emulator's `faults`: the
// frames of a complete bracket, and the camera's gain.
std::vector<json> bracketedFrames(const std::string& mode, const std::string& faults,
                                  double& gain) {
  Emulator emu(mode, {skyFrame(30)}, faults);
  const auto r = emu.run("live /dev/video7" + kBracket + "--frames 24 --sun --coeffs-out " +
                         emu.tmp / "c.jsonl");
  EXPECT_EQ(r.exitCode, 0) << r.output;
  gain = gainOf(r.output);
  std::vector<json> complete;
  for (const json& f : readJsonl(emu.tmp / "c.jsonl"))
    if (f["confidence"]["exposures"] == 3) complete.push_back(f);
  EXPECT_GE(complete.size(), 12u) << r.output;
  return complete;
}

// The still sky through one locked exposure, no bracket: every frame's record.
std::vector<json> oneExposureFrames() {
  Emulator emu("MJPG_256x128", {skyFrame(30)});
  const auto r = emu.run(
      "live /dev/video7 --lock-exposure 0.3 --headless --view-size 64x36 --no-background "
      "--frames 8 --sun --coeffs-out " +
      emu.tmp / "c.jsonl");
  EXPECT_EQ(r.exitCode, 0) << r.output;
  // The sun clipped in every frame: the summary says what measures it.
  EXPECT_NE(r.output.find("hint: the brightest light clipped at 255"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("--bracket -12,-6,0 measures it"), std::string::npos) << r.output;
  return readJsonl(emu.tmp / "c.jsonl");
}

// Every frame's record in the replay of `pattern` (an HDR image sequence: the truth a bracket is
// held to; or a bracket's recording).
std::vector<json> hdrReplay(const std::string& pattern) {
  lpt::TempDir dir;
  const auto r = lpt::runLiveprobe("replay " + pattern +
                                   " --sun --headless --size 64x36 --no-background --quiet "
                                   "--coeffs-out " +
                                   dir / "hdr.jsonl");
  EXPECT_EQ(r.exitCode, 0) << r.output;
  return readJsonl(dir / "hdr.jsonl");
}

json truthOf(const std::string& exr) {
  const auto r = lpt::runLiveprobe("coeffs " + exr + " --sun");
  EXPECT_EQ(r.exitCode, 0) << r.output;
  return json::parse(r.output);
}

// A still sky (one source frame): every merged frame of a complete bracket finds the sun with
// the HDR frame's share and direction. The coefficients: the merge itself is exact to 0.2% of
// L00 (RGB24: no codec between the sensor and the merge); MJPEG's 4:2:0 chroma and quantisation
// move the coloured horizon lights and the sun's disc, 2-4% of L00 on one coefficient, while L00
// stays within 1%.
TEST(LiveHdr, BracketMeasuresTheSun) {
  const json truth = truthOf(skyFrame(30));
  const json& sun = truth["lights"][0];
  for (const auto& [mode, tolerance] : std::vector<std::pair<std::string, double>>{
           {"RGB3_256x128", 0.005}, {"MJPG_256x128", 0.04}}) {
    double gain = 1;
    for (const json& f : bracketedFrames(mode, "control_delay=2", gain)) {
      ASSERT_TRUE(f.contains("lights")) << mode << " frame " << f["frame"];
      const json& l = f["lights"][0];
      EXPECT_NEAR(l["share"].get<double>(), sun["share"].get<double>(),
                  0.1 * sun["share"].get<double>())
          << mode;
      EXPECT_LT(angleDeg(l["direction"], sun["direction"]), 1.0) << mode;
      EXPECT_TRUE(f["confidence"]["brightest_measured"].get<bool>());
      EXPECT_NEAR(f["coefficients"]["L00"][1].get<double>() / gain,
                  truth["coefficients"]["L00"][1].get<double>(),
                  0.02 * truth["coefficients"]["L00"][1].get<double>())
          << mode;
      EXPECT_LT(worstCoefficient(f["coefficients"], truth["coefficients"], gain), tolerance)
          << mode << " frame " << f["frame"];
    }
  }
}

// The synthetic sky's sun turns 18 degrees a second (at 30 frames/s, about 1 degree a frame): a
// merge takes the sun from the bracket's shortest exposure, up to two frames old. It is found
// in every complete bracket, with the HDR share, where the HDR replay has it in one of the
// frames merged.
TEST(LiveHdr, AMovingSunIsFoundInEveryMergedFrame) {
  std::vector<std::string> files;
  for (int i = 0; i < 75; ++i) files.push_back(skyFrame(i));
  const auto truth = hdrReplay(std::string(LIVEPROBE_SOURCE_DIR) + "/recordings/sky-hdr/%04d.exr");
  ASSERT_EQ(truth.size(), 75u);
  Emulator emu("MJPG_256x128", files, "control_delay=2");
  const auto r = emu.run("live /dev/video7" + kBracket + "--frames 40 --sun --coeffs-out " +
                         emu.tmp / "c.jsonl");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  int complete = 0;
  for (const json& f : readJsonl(emu.tmp / "c.jsonl")) {
    if (f["confidence"]["exposures"] != 3) continue;
    ++complete;
    ASSERT_TRUE(f.contains("lights")) << f.dump();
    // The emulator serves source frame `sequence` (mod 75) as the camera's frame `sequence`.
    const long s = f["sequence"].get<long>();
    double nearest = 180;
    for (long k = 0; k < 3; ++k) {
      const json& t = truth[std::size_t((s - k) % 75)]["lights"][0];
      nearest = std::min(nearest, angleDeg(f["lights"][0]["direction"], t["direction"]));
    }
    EXPECT_LT(nearest, 1.0) << "frame " << s;
    const double share = truth[std::size_t(s % 75)]["lights"][0]["share"].get<double>();
    EXPECT_NEAR(f["lights"][0]["share"].get<double>(), share, 0.1 * share) << "frame " << s;
  }
  EXPECT_GE(complete, 30) << r.output;
}

// The shadow the sun casts on the ground, in a render lit by `coeffs` (a coefficients file):
// 1 - shadowed / unshadowed ground, averaged over the pixels `mask` marks (computed from the
// first render when empty: where the shadow darkens the ground by more than 10%).
double groundDarkening(const std::string& coeffs, double exposure, std::vector<bool>& mask,
                       const lpt::TempDir& dir) {
  std::vector<cv::Mat> images;
  for (const std::string shadows : {"--shadows ", ""}) {
    const std::string out = dir / ("ground" + std::to_string(images.size()) + ".png");
    const auto r = lpt::runLiveprobe(
        "render --coeffs " + coeffs + " " + shadows + "--ground --tonemap linear --exposure " +
        std::to_string(exposure) + " --pitch 25 --size 320x180 --headless --out " + out);
    EXPECT_EQ(r.exitCode, 0) << r.output;
    images.push_back(cv::imread(out, cv::IMREAD_GRAYSCALE));
  }
  const cv::Mat& shadowed = images[0];
  const cv::Mat& lit = images[1];
  if (mask.empty())
    for (int i = 0; i < lit.rows * lit.cols; ++i)
      mask.push_back(lp::srgbToLinear(shadowed.data[i] / 255.0f) <
                     0.9f * lp::srgbToLinear(lit.data[i] / 255.0f));
  double sum = 0;
  int count = 0;
  for (int i = 0; i < lit.rows * lit.cols; ++i)
    if (mask[std::size_t(i)]) {
      sum += 1.0 - lp::srgbToLinear(shadowed.data[i] / 255.0f) /
                       std::max(1e-6f, lp::srgbToLinear(lit.data[i] / 255.0f));
      ++count;
    }
  EXPECT_GT(count, 100) << coeffs;
  return count ? sum / count : 0.0;
}

// quarry_01 (a sun over a quarry) at 256x128, turned 1 degree a frame about `axis`: its float
// frames, and each one's HDR replay record (the truth a bracket is held to).
struct TurningQuarry {
  lpt::TempDir dir;
  std::vector<std::string> files;
  std::vector<json> truth;
  TurningQuarry(const double axis[3], int frames)
      : files(lpt::turningFrames(lpt::dataPath("equirect/quarry_01_1k.hdr"), 4, axis, 1.0, frames,
                                 dir.path)),
        truth(hdrReplay(dir / "%04d.exr")) {
    EXPECT_EQ(truth.size(), std::size_t(frames));
  }
};

// A moving run's records against the HDR replay of the same frames (the emulator serves source
// frame `sequence` as the camera's frame `sequence`): no frame whose sun's share is more than 25%
// off the truth says it can be trusted (confidence 0.9 or more), and, counted, the frames whose
// share is within 10% and whose direction is within 1 degree.
struct SunTally {
  int frames = 0, within = 0, aimed = 0;
  std::string misses;  ///< frame: merged share / HDR share

  void add(const json& f, const std::vector<json>& truth, const std::string& what) {
    const long s = f["sequence"].get<long>();
    ASSERT_LT(s, long(truth.size())) << what;
    const json& hdr = truth[std::size_t(s)]["lights"][0];
    const double want = hdr["share"].get<double>();
    const double got = f.contains("lights") ? f["lights"][0]["share"].get<double>() : 0.0;
    if (std::abs(got - want) > 0.25 * want)
      EXPECT_LT(f["confidence"]["value"].get<double>(), 0.9)
          << what << ": frame " << s << " share " << got << " of " << want;
    ++frames;
    within += std::abs(got - want) <= 0.1 * want;
    if (std::abs(got - want) > 0.1 * want)
      misses += " " + std::to_string(s) + ":" + std::to_string(got / want).substr(0, 4);
    if (f.contains("lights"))
      aimed += angleDeg(hdr["direction"], f["lights"][0]["direction"]) <= 1.0;
  }
  /// Each run: 90% or more (the few frames off by 10 to 14% are 8-bit and 4:2:2 noise on a sun
  /// two pixels wide); printed, and added to `all`.
  void report(const std::string& what, SunTally& all) const {
    EXPECT_GE(within, 0.9 * frames) << what << ":" << misses;
    EXPECT_GE(aimed, 0.9 * frames) << what;
    all.frames += frames, all.within += within, all.aimed += aimed;
    std::printf(
        "%s: the sun's share within 10%% in %d of %d frames, its direction within 1 degree in "
        "%d; misses (frame: share / HDR share):%s\n",
        what.c_str(), within, frames, aimed, misses.c_str());
  }
  /// All runs together: `share` of the frames or more (95% unless said).
  void expectAll(double share = 0.95) const {
    EXPECT_GE(within, share * frames);
    EXPECT_GE(aimed, share * frames);
    std::printf(
        "all runs: the share within 10%% in %d of %d frames, the direction within 1 "
        "degree in %d\n",
        within, frames, aimed);
  }
};

// A moving scene: quarry_01 (a sun over a quarry) turned 1 degree a frame about the vertical
// and about a tilted axis, one stop of neutral density, 3 to 5 exposures applied 3 frames late,
// each frame's exposure from the camera's metadata, and without metadata (exposures told from
// the pixels). Against the HDR replay of the same frames, past start-up: the sun's share within
// 10% in at least 95% of the merged frames (90% in each run), its direction within 1 degree in as
// many, and no
// frame whose share is more than 25% off the truth says it can be trusted (confidence 0.9 or
// more). The older frames of each bracket are turned to the newest by the rotation the frames
// show; docs/hdr.md has the counts.
TEST(LiveHdr, AMovingSceneKeepsItsSunOrSaysItLostIt) {
  const double yaw[3] = {0, 0, 1}, tilted[3] = {0.57735, 0.57735, 0.57735};
  constexpr int kFrames = 75;  // more than the run takes: the recording never loops back
  SunTally all;
  for (const double* axis : {yaw, tilted}) {
    const TurningQuarry quarry(axis, kFrames);
    const auto& [files, truth] = std::tie(quarry.files, quarry.truth);
    for (const std::string bracket :
         {"-13,-7,0", "-13,-9,-4,0", "-13,-10,-7,-3,0", "-13,-7,0 without metadata"}) {
      const bool metadata = bracket.find("without") == std::string::npos;
      const std::string what = "axis " + std::to_string(axis[0]) + " bracket " + bracket;
      Emulator emu("YUYV_256x128", files, "control_delay=3");
      emu.env = std::string("LPEMU_SENSITIVITY=0.5 ") + (metadata ? "" : "LPEMU_META_DEVICE= ");
      const auto r = emu.run("live /dev/video7 --bracket " + bracket.substr(0, bracket.find(' ')) +
                             " --lock-exposure 0.3 --headless --view-size 64x36 --no-background "
                             "--frames 58 --sun --coeffs-out " +
                             emu.tmp / "c.jsonl");
      ASSERT_EQ(r.exitCode, 0) << r.output;
      SunTally run;
      // scripts/hdr-pictures plots the first run (yaw, three exposures) from this table.
      const char* table = std::getenv("LIVEPROBE_HDR_MOTION_TABLE");
      std::ofstream plot;
      if (table && axis == yaw && bracket == "-13,-7,0") plot.open(table);
      for (const json& f : readJsonl(emu.tmp / "c.jsonl")) {
        const long s = f["sequence"].get<long>();
        if (s < 14) continue;  // start-up: the lock, the first complete brackets
        run.add(f, truth, what);
        const json& c = f["confidence"];
        plot << s << " " << truth[std::size_t(s)]["lights"][0]["share"] << " "
             << (f.contains("lights") ? f["lights"][0]["share"] : json(0.0)) << " " << c["value"]
             << " " << c["clipped_share"] << " " << c["dark_share"] << " " << c["agreement"]
             << "\n";
      }
      EXPECT_GE(run.frames, 40) << what << "\n" << r.output;
      run.report(what, all);
    }
  }
  all.expectAll();
}

// A camera without a metadata node (most webcams) on a scene that keeps moving: quarry_01
// turned 1 degree a frame about a tilted axis, with one or two stops of neutral density, each
// exposure applied 1 to 3 frames late, through brackets of 3 to 5 exposures. Each frame's
// exposure is the one asked lag frames before it; the pixels only confirm it. Every run
// delivers every frame asked for (a frame left out is not counted as one); no frame more than
// 25% off the HDR replay of the same frames says it can be trusted (confidence 0.9 or more);
// and from the first complete merge on (start-up: the lag told from the first frames, then one
// frame of each exposure), the sun's share within 10% in at least 93% of the frames of all runs
// together (90% in each), its direction within 1 degree in as many.
void turningWithoutMetadata(int delay) {
  const double axis[3] = {0.57735, 0.57735, 0.57735};
  constexpr int kFrames = 75, kAsked = 58;
  const TurningQuarry quarry(axis, kFrames);
  const auto& [files, truth] = std::tie(quarry.files, quarry.truth);
  SunTally all;
  int nd = delay % 2;  // one stop, then two, in turn
  for (const std::string bracket : {"-13,-7,0", "-13,-9,-4,0", "-13,-10,-7,-3,0"}) {
    ++nd;
    const std::string what = "delay " + std::to_string(delay) + ", bracket " + bracket + ", " +
                             std::to_string(nd % 2 + 1) + " stops of ND";
    Emulator emu("YUYV_256x128", files, "control_delay=" + std::to_string(delay));
    emu.env =
        std::string("LPEMU_META_DEVICE= LPEMU_SENSITIVITY=") + (nd % 2 == 0 ? "0.5 " : "0.25 ");
    const auto r = emu.run("live /dev/video7 --bracket " + bracket +
                           " --lock-exposure 0.3 --headless --view-size 64x36 --no-background "
                           "--frames " +
                           std::to_string(kAsked) + " --sun --coeffs-out " + emu.tmp / "c.jsonl");
    ASSERT_EQ(r.exitCode, 0) << what << "\n" << r.output;
    const auto records = readJsonl(emu.tmp / "c.jsonl");
    EXPECT_EQ(records.size(), std::size_t(kAsked)) << what << "\n" << r.output;
    SunTally run, startUp;  // start-up: only its confidence is held to the truth
    bool started = false;
    for (const json& f : records) {
      started = started || f["confidence"]["complete"].get<bool>();
      (started ? run : startUp).add(f, truth, what);
    }
    EXPECT_GE(run.frames, 35) << what << "\n" << r.output;
    run.report(what, all);
  }
  // 93% of the three runs together: the misses sit 10 to 14% off, and a loaded machine, whose
  // late requests shift the schedule, moves a frame or two of them across 10% (151 of 160 at
  // delay 1 under load, 153 idle).
  all.expectAll(0.93);
}

// One run of a turning map on the emulated YUYV camera, with or without the metadata node: its
// records, the exposure the camera had on each frame it served (its log), and where the
// comparison starts (two brackets after its first complete merge).
struct TurningRun {
  std::vector<json> records;
  std::vector<std::string> schedule;
  long started = -1;
  std::string output;
  std::set<long> recordedFrom(long first) const {
    std::set<long> s;
    for (const json& f : records)
      if (f["sequence"].get<long>() >= first) s.insert(f["sequence"].get<long>());
    return s;
  }
};

TurningRun turningRun(const std::vector<std::string>& files, bool metadata) {
  Emulator emu("YUYV_256x128", files, "control_delay=2");
  emu.env = std::string("LPEMU_SENSITIVITY=0.5 ") + (metadata ? "" : "LPEMU_META_DEVICE= ");
  TurningRun run;
  const auto r = emu.run(
      "live /dev/video7 --bracket -13,-9,-4,0 --lock-exposure 0.3 --headless --view-size "
      "64x36 --no-background --frames 50 --sun --coeffs-out " +
      emu.tmp / "c.jsonl");
  run.output = r.output;
  EXPECT_EQ(r.exitCode, 0) << r.output;
  if (r.exitCode != 0) return run;
  run.records = readJsonl(emu.tmp / "c.jsonl");
  for (const json& f : run.records)
    if (f["confidence"]["complete"].get<bool>()) {
      run.started = f["sequence"].get<long>() + 8;
      break;
    }
  std::istringstream log(emu.logText());
  for (std::string line; std::getline(log, line);)
    if (line.rfind("frame ", 0) == 0) run.schedule.push_back(line);
  return run;
}

// The two runs saw the same frames at the same exposures: the camera served both the same
// schedule, and from a bracket before the comparison starts both recorded the same frames.
bool sameFrames(const TurningRun& a, const TurningRun& b) {
  if (a.started < 0 || b.started < 0) return false;
  const long until =
      std::min(a.records.back()["sequence"].get<long>(), b.records.back()["sequence"].get<long>());
  const auto n = std::size_t(until + 1);
  if (a.schedule.size() < n || b.schedule.size() < n ||
      !std::equal(a.schedule.begin(), a.schedule.begin() + long(n), b.schedule.begin()))
    return false;
  const long from = std::max(a.started, b.started) - 8;
  auto sa = a.recordedFrom(from), sb = b.recordedFrom(from);
  std::erase_if(sa, [&](long s) { return s > until; });
  std::erase_if(sb, [&](long s) { return s > until; });
  return sa == sb;
}

// The schedule names a frame's exposure as the camera's metadata would: on other maps turned
// about another tilted axis (a dim overpass whose first frames the pixels cannot name while it
// turns; a bright esplanade whose -9 EV frame the pixels, through 4:2:2 chroma, measure a third
// of a stop off; a sunrise), the same run without the metadata node gives, frame for frame from
// two brackets after the first complete merge on, the records of the run with it: the coefficients
// within 1e-3 of L00, the confidence within 0.01, the brightest light measured or not alike.
// This holds where the two runs saw the same frames at the same exposures: a run that drops a
// frame, or sets a stop a frame late because the machine held it up, sees another schedule (the
// camera's log and the records say so), and the pair is run again, up to three times.
TEST(LiveHdr, WithoutMetadataAsWithIt) {
  const double axis[3] = {0.8, 0, 0.6};
  for (const std::string map : {"pedestrian_overpass", "royal_esplanade", "blouberg_sunrise_2"}) {
    lpt::TempDir dir;
    const auto files = lpt::turningFrames(lpt::dataPath("equirect/" + map + "_1k.hdr"), 4, axis,
                                          1.0, 80, dir.path);
    TurningRun with, without;
    for (int attempt = 1; attempt <= 3; ++attempt) {
      with = turningRun(files, true);
      without = turningRun(files, false);
      if (with.records.empty() || without.records.empty() || sameFrames(with, without)) break;
      std::printf("%s: the two runs saw different frames%s\n", map.c_str(),
                  attempt < 3 ? "; run again" : "; compared as they are");
    }
    ASSERT_FALSE(with.records.empty() || without.records.empty()) << map;
    EXPECT_EQ(with.records.size(), 50u) << map;
    EXPECT_EQ(without.records.size(), 50u) << map;
    std::map<long, json> byFrame;
    for (const json& f : with.records)
      if (with.started >= 0 && f["sequence"].get<long>() >= with.started)
        byFrame[f["sequence"].get<long>()] = f;
    int compared = 0;
    for (const json& f : without.records) {
      const long s = f["sequence"].get<long>();
      if (without.started < 0 || s < without.started || !byFrame.count(s)) continue;
      ++compared;
      // (The turn the merge estimates from the last two brackets differs at first: the frames
      // before the lag is known are not merged.)
      EXPECT_LT(worstCoefficient(f["coefficients"], byFrame[s]["coefficients"], 1.0), 1e-3)
          << map << ": frame " << s;
      const json &c = f["confidence"], &d = byFrame[s]["confidence"];
      EXPECT_NEAR(c["value"].get<double>(), d["value"].get<double>(), 0.01) << map << " " << s;
      EXPECT_EQ(c["brightest_measured"], d["brightest_measured"]) << map << ": frame " << s;
    }
    EXPECT_GE(compared, 25) << map << "\n" << without.output;
    if (HasFailure())
      std::printf("with metadata:\n%s\nwithout:\n%s\n", with.output.c_str(),
                  without.output.c_str());
  }
}

TEST(LiveHdr, ATurningSceneWithoutMetadataDelay1) { turningWithoutMetadata(1); }
TEST(LiveHdr, ATurningSceneWithoutMetadataDelay2) { turningWithoutMetadata(2); }
TEST(LiveHdr, ATurningSceneWithoutMetadataDelay3) { turningWithoutMetadata(3); }

// The shadow a bracket's sun casts is as dark as the HDR frame's: the ground under the model is
// darkened within 10% as much; one 8-bit exposure finds no sun to cast one.
TEST(LiveHdr, TheBracketsSunCastsTheHdrShadow) {
  lpt::TempDir dir;
  const std::string hdr = dir / "hdr.json";
  std::ofstream(hdr) << truthOf(skyFrame(30)).dump();
  Emulator emu("MJPG_256x128", {skyFrame(30)}, "control_delay=2");
  const auto r = emu.run("live /dev/video7" + kBracket + "--frames 16 --sun --coeffs-out " +
                         emu.tmp / "c.jsonl");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const double gain = gainOf(r.output);
  std::ofstream(dir / "merged.json") << readJsonl(emu.tmp / "c.jsonl").back().dump();
  std::vector<bool> shadow;
  const double truth = groundDarkening(hdr, 1.0, shadow, dir);
  const double merged = groundDarkening(dir / "merged.json", 1.0 / gain, shadow, dir);
  EXPECT_GT(truth, 0.3);
  EXPECT_NEAR(merged, truth, 0.1 * truth);
  std::ofstream(dir / "plain.json") << oneExposureFrames().back().dump();
  EXPECT_LT(groundDarkening(dir / "plain.json", 1.0 / gain, shadow, dir), 0.1 * truth);
  std::printf("ground darkening: HDR %.3f, bracket %.3f\n", truth, merged);
}

// The same camera without bracketing: exposed for the sky (median at mid-grey), it clips the sun
// and cannot know it: the brightest pixel is not measured, and what is found of the sun holds a
// few percent of the power at most, against 46% in the HDR frame. A bracket too short to reach
// the sun (-4,0) finds it, marked clipped, its share a lower bound.
TEST(LiveHdr, ASunTheExposuresCannotReachIsALowerBound) {
  for (const json& f : oneExposureFrames()) {
    EXPECT_FALSE(f["confidence"]["brightest_measured"].get<bool>());
    EXPECT_GT(f["confidence"]["clipped_share"].get<double>(), 0.0);
    if (f.contains("lights")) EXPECT_LT(f["lights"][0]["share"].get<double>(), 0.05);
  }
  Emulator emu("MJPG_256x128", {skyFrame(30)}, "control_delay=2");
  const auto r = emu.run(
      "live /dev/video7 --bracket -4,0 --lock-exposure 0.3 --headless --view-size 64x36 "
      "--no-background --frames 12 --sun --coeffs-out " +
      emu.tmp / "c.jsonl");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  int complete = 0;
  for (const json& f : readJsonl(emu.tmp / "c.jsonl")) {
    if (f["confidence"]["exposures"] != 2) continue;
    ++complete;
    EXPECT_FALSE(f["confidence"]["brightest_measured"].get<bool>());
    ASSERT_TRUE(f.contains("lights")) << f.dump();
    EXPECT_TRUE(f["lights"][0]["clipped"].get<bool>());
    EXPECT_LT(f["lights"][0]["share"].get<double>(), 0.2);
  }
  EXPECT_GE(complete, 5);
}

// A camera that applies a new exposure three frames late and only in powers of two (100 us
// units: 60 becomes 64, 3859 becomes 4096): the merge divides by what each frame reports, so L00
// is right; dividing by what was asked would be 6% off.
TEST(LiveHdr, LateAndRoundedExposuresAreTakenAsReported) {
  const json truth = truthOf(skyFrame(30));
  double gain = 1;
  for (const json& f : bracketedFrames("RGB3_256x128", "control_delay=3,exposure_pow2", gain))
    EXPECT_LT(worstCoefficient(f["coefficients"], truth["coefficients"], gain), 0.005);
}

// A camera without a metadata node (most webcams), taking each exposure 1 to 3 frames late:
// each frame's exposure is the schedule's, confirmed by its pixels, and every complete bracket
// of the still sky meets the targets of the camera that reports them (the sun's share within
// 10% and 1 degree, L00 within 2%). A camera that also rounds what it is asked to a power of two,
// and says so nowhere, is merged at what was asked: L00 is off by the locked exposure's rounding
// (3859 taken as 4096 x 100 us: 6.1% over), predicted within 2%, and the sun still within 10%.
TEST(LiveHdr, ABracketWithoutMetadataToldFromThePixels) {
  const json truth = truthOf(skyFrame(30));
  const json& sun = truth["lights"][0];
  const double l00 = truth["coefficients"]["L00"][1].get<double>();
  for (const std::string faults :
       {"control_delay=1", "control_delay=2", "control_delay=3", "control_delay=3,exposure_pow2"}) {
    Emulator emu("MJPG_256x128", {skyFrame(30)}, faults);
    emu.env = "LPEMU_META_DEVICE= ";  // no metadata node beside the camera
    const auto r = emu.run("live /dev/video7" + kBracket + "--frames 30 --sun --coeffs-out " +
                           emu.tmp / "c.jsonl");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("each frame's exposure measured from its pixels"), std::string::npos)
        << r.output;
    const double gain = gainOf(r.output);
    double rounding = 1;  // what a silent power of two does to the locked (0 EV) exposure
    if (faults.find("exposure_pow2") != std::string::npos) {
      std::smatch m;
      ASSERT_TRUE(std::regex_search(r.output, m, std::regex("exposure ([0-9]+) x 100 us")));
      const double locked = std::stod(m[1]);
      rounding = std::exp2(std::round(std::log2(locked))) / locked;
    }
    int complete = 0;
    for (const json& f : readJsonl(emu.tmp / "c.jsonl")) {
      if (f["confidence"]["exposures"] != 3) continue;
      ++complete;
      ASSERT_TRUE(f.contains("lights")) << faults << " frame " << f["frame"];
      const json& l = f["lights"][0];
      EXPECT_NEAR(l["share"].get<double>(), sun["share"].get<double>(),
                  0.1 * sun["share"].get<double>())
          << faults << " frame " << f["frame"];
      EXPECT_LT(angleDeg(l["direction"], sun["direction"]), 1.0) << faults;
      EXPECT_NEAR(f["coefficients"]["L00"][1].get<double>() / gain, rounding * l00, 0.02 * l00)
          << faults << " frame " << f["frame"];
    }
    EXPECT_GE(complete, 20) << faults << "\n" << r.output;
  }
}

// The sun clipped even at the shortest exposure is said once, in the first cycles, with what
// measures it: neutral density where the stop is at the control's limit (the emulated sensor 8
// times as sensitive: -12 EV is 1 x 100 us), a shorter stop where it is not (-6,-3,0); every
// record's confidence is then at most 0.5 and its light clipped. One stop of neutral density
// (a sensor 4 times as sensitive) measures the sun: nothing is said.
TEST(LiveHdr, ASunClippedAtTheShortestExposureIsSaidOnce) {
  struct Case {
    std::string sensitivity, bracket, said;
  };
  for (const Case& c : std::vector<Case>{
           {"8", kBracket,
            "warning: /dev/video7: the brightest light clips even at -12 EV (1 x 100 us, the "
            "control's limit): its share is a lower bound (confidence at most 0.5); add neutral "
            "density, a stop at a time, until a run no longer says this ("},
           {"1",
            " --bracket -6,-3,0 --lock-exposure 0.3 --headless --view-size 64x36 "
            "--no-background ",
            "warning: /dev/video7: the brightest light clips even at -6 EV (60 x 100 us, the "
            "shortest of the bracket): a shorter stop measures it (the control goes down to 1 x "
            "100 us)"},
           {"4", kBracket, ""}}) {
    Emulator emu("RGB3_256x128", {skyFrame(30)}, "control_delay=2");
    emu.env = "LPEMU_SENSITIVITY=" + c.sensitivity + " ";
    const auto r = emu.run("live /dev/video7" + c.bracket + "--frames 15 --sun --coeffs-out " +
                           emu.tmp / "c.jsonl");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const std::size_t at = r.output.find("the brightest light clips even at");
    if (c.said.empty()) {
      EXPECT_EQ(at, std::string::npos) << r.output;
      continue;
    }
    EXPECT_NE(r.output.find(c.said), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("the brightest light clips even at", at + 1), std::string::npos)
        << "said twice:\n"
        << r.output;
    for (const json& f : readJsonl(emu.tmp / "c.jsonl")) {
      if (!f["confidence"]["complete"].get<bool>()) continue;
      EXPECT_LE(f["confidence"]["value"].get<double>(), 0.5) << "frame " << f["frame"];
      EXPECT_FALSE(f["confidence"]["brightest_measured"].get<bool>()) << "frame " << f["frame"];
      ASSERT_TRUE(f.contains("lights")) << "frame " << f["frame"];
      EXPECT_TRUE(f["lights"][0]["clipped"].get<bool>()) << "frame " << f["frame"];
    }
  }
}

// Cameras that cannot bracket say so in one line and exit 1.
TEST(LiveHdr, CamerasThatCannotBracketAreRefused) {
  const std::vector<std::tuple<std::string, std::string, std::string>> cases = {
      {"no_exposure", "", "no exposure time control"},
      {"refuse=" + std::to_string(V4L2_CID_EXPOSURE_ABSOLUTE), "", "Device or resource busy"},
      {"ignore_exposure", "", "ignores its exposure control"},
      {"", "--metadata /dev/video9", "no per-frame exposure times: /dev/video9"},
  };
  for (const auto& [faults, extra, says] : cases) {
    Emulator emu("MJPG_256x128", {skyFrame(30)}, faults);
    const auto r = emu.run("live /dev/video7" + kBracket + "--frames 40 " + extra);
    EXPECT_EQ(r.exitCode, 1) << faults << "\n" << r.output;
    const std::string last = r.output.substr(r.output.rfind('\n', r.output.size() - 2) + 1);
    EXPECT_NE(last.find(says), std::string::npos) << faults << "\n" << r.output;
  }
  Emulator emu("MJPG_256x128", {skyFrame(30)});
  for (const std::string& bad : {"-12", "-12,-12,0", "-30,0", "1,2,3,4,5,6", "a,0"}) {
    const auto r = emu.run("live /dev/video7 --bracket " + bad);
    EXPECT_EQ(r.exitCode, 1) << bad;
    EXPECT_EQ(lpt::lineCount(r.output), 1) << r.output;
    EXPECT_NE(r.output.find("--bracket"), std::string::npos) << r.output;
  }
}

// The plan says why a stop is not the one asked: the control's range clamps -14 EV of the
// locked 3859 x 100 us to 1 (-11.9 EV), while -11.5 EV (1.33) is 1 because the control counts
// whole 100 us.
TEST(LiveHdr, TheBracketPlanSaysWhyAStopMoved) {
  Emulator emu("RGB3_256x128", {skyFrame(30)});
  for (const auto& [stops, says] : std::vector<std::pair<std::string, std::string>>{
           {"-14,-6,0", "-14 EV is -11.9 EV, the control's limit"},
           {"-11.5,-6,0", "-11.5 EV is -11.9 EV, the nearest whole 100 us"}}) {
    const auto r = emu.run("live /dev/video7 --bracket " + stops +
                           " --lock-exposure 0.3 --headless --view-size 64x36 --frames 2");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find(says), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find(";;"), std::string::npos) << r.output;
  }
}

// A camera whose response is a gamma of 2.6: --gamma 2.6 is the merge's curve, and the still
// sky's targets hold in every complete bracket (the sun's share within 10%, L00 within 2%).
// Merged as sRGB, the exposures contradict each other, no frame comes near, and the summary
// says to calibrate.
TEST(LiveHdr, GammaIsTheMergesResponse) {
  const json truth = truthOf(skyFrame(30));
  const double share = truth["lights"][0]["share"].get<double>();
  const double l00 = truth["coefficients"]["L00"][1].get<double>();
  for (const std::string gamma : {"--gamma 2.6 ", ""}) {
    Emulator emu("RGB3_256x128", {skyFrame(30)}, "control_delay=2");
    emu.env = "LPEMU_RESPONSE=gamma=2.6 ";
    const auto r = emu.run("live /dev/video7" + kBracket + gamma +
                           "--frames 18 --sun --coeffs-out " + emu.tmp / "c.jsonl");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const double gain = gainOf(r.output);
    int complete = 0, near = 0;
    for (const json& f : readJsonl(emu.tmp / "c.jsonl")) {
      const double ratio = f["coefficients"]["L00"][1].get<double>() / gain / l00;
      near += std::abs(ratio - 1.0) <= 0.02;
      if (gamma.empty() || f["confidence"]["exposures"] != 3) continue;
      ++complete;
      EXPECT_NEAR(ratio, 1.0, 0.02) << "frame " << f["frame"];
      ASSERT_TRUE(f.contains("lights")) << "frame " << f["frame"];
      EXPECT_NEAR(f["lights"][0]["share"].get<double>(), share, 0.1 * share);
    }
    // Merged as sRGB, the summary says the exposures disagree and what measures the response.
    const bool hinted = r.output.find("hint: the exposures disagree") != std::string::npos &&
                        r.output.find("liveprobe calibrate DEVICE") != std::string::npos;
    EXPECT_EQ(hinted, gamma.empty()) << r.output;
    if (gamma.empty())
      EXPECT_EQ(near, 0) << r.output;
    else
      EXPECT_GE(complete, 8) << r.output;
  }
}

// `recording` replayed gives the live run's records (`live`, a --coeffs-out file), to the last
// digit: frame numbers, coefficients, lights and confidence.
void expectReplayAsLive(const std::string& recording, const std::string& live,
                        const std::string& what) {
  const auto a = readJsonl(live), b = hdrReplay(recording);
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i]["sequence"], b[i]["sequence"]) << what << " frame " << i;
    EXPECT_EQ(a[i]["coefficients"], b[i]["coefficients"]) << what << " frame " << i;
    EXPECT_EQ(a[i].value("lights", json()), b[i].value("lights", json())) << what << " " << i;
    EXPECT_EQ(a[i]["confidence"], b[i]["confidence"]) << what << " frame " << i;
  }
}

// A bracketed recording replays through the same merge, frame for frame: the coefficients,
// lights and confidence are the live run's, to the last digit. In each container that keeps the
// codes losslessly with every frame's exposure: .mkv (FFV1), .png frames (their sidecar beside
// them, replayed by pattern or by folder).
TEST(LiveHdr, ABracketedRecordingReplaysAsLive) {
  for (const auto& [record, replayed] : std::vector<std::pair<std::string, std::string>>{
           {"b.mkv", "b.mkv"}, {"png/%04d.png", "png/%04d.png"}, {"dir/%04d.png", "dir"}}) {
    Emulator emu("MJPG_256x128", {skyFrame(10), skyFrame(11), skyFrame(12)}, "control_delay=2");
    fs::create_directories(emu.tmp.path / fs::path(record).parent_path());
    const auto live = emu.run("live /dev/video7" + kBracket + "--frames 20 --sun --coeffs-out " +
                              emu.tmp / "live.jsonl --record " + emu.tmp / record);
    ASSERT_EQ(live.exitCode, 0) << live.output;
    expectReplayAsLive(emu.tmp / replayed, emu.tmp / "live.jsonl", record);
  }
}

// Without a metadata node too, a bracketed recording replays as the live run went, frame for
// frame, on a still sky and on a turning scene: the frames left out before the camera's delay
// was known leave gaps in the frame numbers, which the sidecar keeps, and the merge turns the
// older frames by them.
TEST(LiveHdr, ABracketWithoutMetadataReplaysAsLive) {
  const double axis[3] = {0.57735, 0.57735, 0.57735};
  lpt::TempDir turning;
  const auto quarry = lpt::turningFrames(lpt::dataPath("equirect/quarry_01_1k.hdr"), 4, axis, 1.0,
                                         40, turning.path);
  for (const auto& [what, files, mode] :
       std::vector<std::tuple<std::string, std::vector<std::string>, std::string>>{
           {"still sky", {skyFrame(30)}, "MJPG_256x128"},
           {"turning quarry", quarry, "YUYV_256x128"}}) {
    Emulator emu(mode, files, "control_delay=2");
    emu.env = "LPEMU_META_DEVICE= LPEMU_SENSITIVITY=0.5 ";
    const auto live = emu.run(
        "live /dev/video7 --bracket -13,-10,-7,-3,0 --lock-exposure 0.3 --headless "
        "--view-size 64x36 --no-background --frames 25 --sun --coeffs-out " +
        emu.tmp / "live.jsonl --record " + emu.tmp / "b.mkv");
    ASSERT_EQ(live.exitCode, 0) << live.output;
    EXPECT_NE(live.output.find("left out of the bracket"), std::string::npos) << live.output;
    expectReplayAsLive(emu.tmp / "b.mkv", emu.tmp / "live.jsonl", what);
  }
}

// The bracket merged on the GPU (--projection gpu: the capture thread's EGL context; Mesa's
// llvmpipe here) against the CPU's merge of the same frames: the live run's recording, replayed
// with --projection cpu, goes through the CPU's merge frame for frame. A still sky with the light
// search (the merged frame read back for it) and a turning quarry without metadata (the older
// frames turned to the newest), each projected as it merges: every frame's coefficients within
// 1e-3 of L00, its confidence within 0.01, its sun's share within 1%; and every frame drawn
// from the frame kept on the GPU as from the CPU's.
TEST(LiveHdr, TheBracketMergedOnTheGpuIsTheCpusMerge) {
  const double axis[3] = {0.57735, 0.57735, 0.57735};
  lpt::TempDir turning;
  const auto quarry = lpt::turningFrames(lpt::dataPath("equirect/quarry_01_1k.hdr"), 4, axis, 1.0,
                                         40, turning.path);
  for (const auto& [what, files, mode, args] :
       std::vector<std::tuple<std::string, std::vector<std::string>, std::string, std::string>>{
           {"still sky", {skyFrame(30)}, "MJPG_256x128", kBracket + "--sun "},
           {"turning quarry", quarry, "YUYV_256x128",
            " --bracket -13,-10,-7,-3,0 --lock-exposure 0.3 --headless --view-size 64x36 "
            "--no-background "}}) {
    Emulator emu(mode, files, "control_delay=2");
    if (what == "turning quarry") emu.env = "LPEMU_META_DEVICE= LPEMU_SENSITIVITY=0.5 ";
    const auto live =
        emu.run("live /dev/video7" + args + "--frames 20 --gl egl --projection gpu " +
                "--coeffs-out " + emu.tmp / "gpu.jsonl --record " + emu.tmp / "b.mkv");
    ASSERT_EQ(live.exitCode, 0) << live.output;
    EXPECT_NE(live.output.find("bracket merged on the GPU: 20 of 20 frames"), std::string::npos)
        << live.output;
    const bool sun = args.find("--sun") != std::string::npos;
    // The merged frame stays on the GPU for the display (the two EGL contexts share objects);
    // with the light search a copy comes back for it.
    const std::string kept = "20 of 20 frames, 20 kept there for the background";
    EXPECT_NE(live.output.find(kept), std::string::npos) << live.output;
    const std::string replay = "replay " + emu.tmp / "b.mkv" + (sun ? " --sun" : "") +
                               " --headless --size 64x36 --exposure 1 --gl egl ";
    const auto cpu = lpt::runLiveprobe(replay + "--quiet --projection cpu --out-dir " +
                                       emu.tmp / "cpu" + " --coeffs-out " + emu.tmp / "cpu.jsonl");
    ASSERT_EQ(cpu.exitCode, 0) << cpu.output;
    // The recording replayed with its backgrounds drawn: from the GPU's frame as from the CPU's.
    const auto gpuDrawn =
        lpt::runLiveprobe(replay + "--projection gpu --out-dir " + emu.tmp / "gpu");
    ASSERT_EQ(gpuDrawn.exitCode, 0) << gpuDrawn.output;
    EXPECT_NE(gpuDrawn.output.find(kept), std::string::npos) << gpuDrawn.output;
    double drawnWorst = 0;
    for (int i = 0; i < 20; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "/frame_%06d.png", i);
      const cv::Mat a = cv::imread(emu.tmp / "cpu" + name), b = cv::imread(emu.tmp / "gpu" + name);
      ASSERT_FALSE(a.empty() || b.empty()) << what << name;
      cv::Mat diff;
      cv::absdiff(a, b, diff);
      double most = 0;
      cv::minMaxLoc(diff.reshape(1), nullptr, &most);
      drawnWorst = std::max(drawnWorst, most);
    }
    EXPECT_LE(drawnWorst, 1.0) << what << ": the drawn frames differ";
    const auto g = readJsonl(emu.tmp / "gpu.jsonl"), c = readJsonl(emu.tmp / "cpu.jsonl");
    ASSERT_EQ(g.size(), c.size()) << what;
    double worst = 0, worstConfidence = 0;
    for (std::size_t i = 0; i < g.size(); ++i) {
      EXPECT_EQ(g[i]["sequence"], c[i]["sequence"]) << what << " frame " << i;
      worst = std::max(worst, worstCoefficient(g[i]["coefficients"], c[i]["coefficients"], 1.0));
      worstConfidence =
          std::max(worstConfidence, std::abs(g[i]["confidence"]["value"].get<double>() -
                                             c[i]["confidence"]["value"].get<double>()));
      EXPECT_EQ(g[i].contains("lights"), c[i].contains("lights")) << what << " frame " << i;
      if (g[i].contains("lights") && c[i].contains("lights")) {
        const double share = c[i]["lights"][0]["share"].get<double>();
        EXPECT_NEAR(g[i]["lights"][0]["share"].get<double>(), share, 0.01 * share)
            << what << " frame " << i;
      }
    }
    EXPECT_LT(worst, 1e-3) << what;
    EXPECT_LT(worstConfidence, 0.01) << what;
    std::printf(
        "%s: %zu frames merged on the GPU, the CPU's merge within %.2g of L00, confidence "
        "within %.2g\n",
        what.c_str(), g.size(), worst, worstConfidence);
  }
}

// In a window (GLFW's EGL context, under Xvfb on Mesa's llvmpipe) the bracket merged on the GPU
// stays there for the background as it does headless: the capture thread's EGL context shares
// the window's objects, on the window's display.
TEST(LiveHdr, AWindowDrawsTheMergedFrameWhereTheGpuMergedIt) {
  Emulator emu("MJPG_256x128", {skyFrame(30)}, "control_delay=2");
  emu.prefix = lpt::xvfbRun("320x240x24");
  const auto r = emu.run(
      "live /dev/video7 --bracket -12,-6,0 --lock-exposure 0.3 --view-size 160x90 --no-hud "
      "--frames 12 --projection gpu");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("GLFW window, EGL"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bracket merged on the GPU: 12 of 12 frames, 12 kept there for the "
                          "background (not read back)"),
            std::string::npos)
      << r.output;
}

// A container that would not replay the merge is refused before the camera opens, in one line
// that names it, and nothing is written: MJPEG (.avi) and H.264 (.mp4) are lossy; .exr frames
// keep radiance, not the codes.
TEST(LiveHdr, ABracketGoesOnlyWhereItReplays) {
  Emulator emu("MJPG_256x128", {skyFrame(30)});
  for (const std::string record : {"b.avi", "b.mp4", "%04d.exr"}) {
    const auto r =
        emu.run("live /dev/video7" + kBracket + "--frames 5 --record " + emu.tmp / record);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_EQ(lpt::lineCount(r.output), 1) << r.output;
    EXPECT_NE(r.output.find(record + ": a bracket is recorded losslessly"), std::string::npos)
        << r.output;
  }
  EXPECT_EQ(emu.logText().find("open"), std::string::npos) << emu.logText();
  for (const auto& e : fs::directory_iterator(emu.tmp.path))  // the modes, the call log
    EXPECT_TRUE(e.path().filename() == "modes" || e.path() == emu.log()) << e.path();
}

// A hand over the lens (10 frames gone dark, or white), starting on each exposure of the bracket
// in turn, with the camera's metadata and without it (the hand's frames then named by the
// schedule, the run going on): its first frame has confidence below 0.5 (a dark -12 EV frame is
// what a short exposure of the sky reads, bar the sun it contradicts), every frame it covers is
// held at the last good lighting, and the hold ends only on a complete bracket that agrees again
// (every exposure merged, the sun measured unclipped), whose sun then has the HDR share: within 3
// frames of the hand's going.
TEST(LiveHdr, HoldBelowKeepsTheLightingThroughAnOccluder) {
  const json truth = truthOf(skyFrame(30));
  const double share = truth["lights"][0]["share"].get<double>();
  for (const bool metadata : {true, false})
    for (const std::string how : {"", ",occlude_white"})
      for (const int from : {30, 31, 32}) {
        const std::string what = (how.empty() ? "dark from " : "white from ") +
                                 std::to_string(from) + (metadata ? "" : ", no metadata");
        Emulator emu(
            "MJPG_256x128", {skyFrame(30)},
            "control_delay=2,occlude_frames=10,occlude_from=" + std::to_string(from) + how);
        if (!metadata) emu.env = "LPEMU_META_DEVICE= ";
        const auto r =
            emu.run("live /dev/video7" + kBracket +
                    "--frames 50 --sun --hold-below 0.5 --coeffs-out " + emu.tmp / "c.jsonl");
        ASSERT_EQ(r.exitCode, 0) << r.output;
        json good;
        int held = 0;
        long released = -1;
        for (const json& f : readJsonl(emu.tmp / "c.jsonl")) {
          const long s = f["sequence"].get<long>();
          const bool isHeld = f["confidence"]["held"].get<bool>();
          held += isHeld;
          if (s == from) EXPECT_LT(f["confidence"]["value"].get<double>(), 0.5) << what;
          if (s >= from && s < from + 10) EXPECT_TRUE(isHeld) << what << ": frame " << s;
          if (isHeld) {
            EXPECT_EQ(f["coefficients"], good["coefficients"]) << what << ": frame " << s;
          } else if (s < from) {
            good = f;
          } else {
            if (released < 0) released = s;
            EXPECT_TRUE(f["confidence"]["complete"].get<bool>()) << what << ": frame " << s;
            ASSERT_TRUE(f.contains("lights")) << what << ": frame " << s;
            EXPECT_NEAR(f["lights"][0]["share"].get<double>(), share, 0.1 * share)
                << what << ": frame " << s;
          }
        }
        EXPECT_GE(released, from + 10) << what;
        EXPECT_LE(released, from + 13) << what;
        EXPECT_NE(r.output.find(std::to_string(held) + " held"), std::string::npos) << r.output;
      }
}

// calibrate on cameras whose responses are sRGB, a gamma of 1.8 and one of 2.6: every code from
// lp::kDarkestCode to lp::kBrightestCode, in every channel, within 3% of the camera's curve (up
// to the one scale a response leaves open, fitted over codes 32-240); the sweep goes below its
// -6 EV as far as the darkest codes need. A bracket merged live with the recovered response
// meets the still sky's targets: the sun's share within 10%, L00 within 2% (after that scale).
TEST(LiveHdr, CalibrateRecoversTheResponse) {
  const json truth = truthOf(skyFrame(30));
  const double share = truth["lights"][0]["share"].get<double>();
  const double l00 = truth["coefficients"]["L00"][1].get<double>();
  for (const auto& [what, gamma] : std::vector<std::pair<std::string, double>>{
           {"srgb", 0}, {"gamma=1.8", 1.8}, {"gamma=2.6", 2.6}}) {
    Emulator emu("RGB3_256x128", {skyFrame(30)}, "control_delay=2");
    emu.env = "LPEMU_RESPONSE=" + what + " ";
    const auto cal =
        emu.run("calibrate /dev/video7 --lock-exposure 0.3 --out " + emu.tmp / "r.json");
    ASSERT_EQ(cal.exitCode, 0) << what << "\n" << cal.output;
    const lp::CameraResponse response = lp::CameraResponse::load(emu.tmp / "r.json");
    const auto camera = [&](int code) {
      const double v = code / 255.0;
      return gamma > 0 ? std::pow(v, gamma) : double(lp::srgbToLinear(float(v)));
    };
    double logScale = 0;
    for (int code = 32; code <= 240; ++code)
      logScale += std::log(response.linear[1][std::size_t(code)] / camera(code)) / 209;
    const double scale = std::exp(logScale);
    for (int c = 0; c < 3; ++c)
      for (int code = lp::kDarkestCode; code <= lp::kBrightestCode; ++code)
        EXPECT_NEAR(response.linear[std::size_t(c)][std::size_t(code)] / scale / camera(code), 1.0,
                    0.03)
            << what << ": channel "
            << "RGB"[c] << ", code " << code;
    EXPECT_LE(response.readFrom, lp::kDarkestCode + 1) << what << "\n" << cal.output;
    EXPECT_EQ(response.controlDelay, 2) << what << "\n" << cal.output;

    const auto live = emu.run("live /dev/video7" + kBracket + "--frames 15 --sun --response " +
                              emu.tmp / "r.json --coeffs-out " + emu.tmp / "c.jsonl");
    ASSERT_EQ(live.exitCode, 0) << what << "\n" << live.output;
    EXPECT_EQ(live.output.find("a new exposure showed"), std::string::npos) << live.output;
    const double gain = gainOf(live.output);
    int complete = 0;
    for (const json& f : readJsonl(emu.tmp / "c.jsonl")) {
      if (f["confidence"]["exposures"] != 3) continue;
      ++complete;
      EXPECT_NEAR(f["coefficients"]["L00"][1].get<double>() / gain / scale, l00, 0.02 * l00)
          << what << ": frame " << f["frame"];
      ASSERT_TRUE(f.contains("lights")) << what << ": frame " << f["frame"];
      EXPECT_NEAR(f["lights"][0]["share"].get<double>(), share, 0.1 * share)
          << what << ": frame " << f["frame"];
    }
    EXPECT_GE(complete, 8) << what << "\n" << live.output;
  }

  for (const std::string& faults : {"no_exposure", "ignore_exposure"}) {
    Emulator bad("RGB3_256x128", {skyFrame(30)}, faults);
    const auto r = bad.run("calibrate /dev/video7 --lock-exposure 0.2 --out " + bad.tmp / "r.json");
    EXPECT_EQ(r.exitCode, 1) << faults << "\n" << r.output;
    EXPECT_FALSE(fs::exists(bad.tmp / "r.json"));
    EXPECT_NE(r.output.find(faults == "no_exposure" ? "no exposure time control" : "ignores"),
              std::string::npos)
        << r.output;
  }
}

// calibrate through YUYV: the response from the pixels whose pair reads one colour, within 3% of
// the camera's sRGB curve from code lp::kYuvTrustedFrom up in every channel, and a warning that
// names the format and the one that reaches every code.
TEST(LiveHdr, CalibrateThroughYuyvSaysWhatItHolds) {
  Emulator emu("YUYV_256x128", {lpt::dataPath("equirect/quarry_01_1k.hdr")}, "control_delay=2");
  const auto cal = emu.run("calibrate /dev/video7 --lock-exposure 0.3 --out " + emu.tmp / "r.json");
  ASSERT_EQ(cal.exitCode, 0) << cal.output;
  EXPECT_NE(cal.output.find("warning: /dev/video7 sends YUYV, which shares each pixel's colour "
                            "with its neighbours': the response holds within 3% from code " +
                            std::to_string(lp::kYuvTrustedFrom) + " up"),
            std::string::npos)
      << cal.output;
  EXPECT_NE(cal.output.find("--pixel-format rgb24"), std::string::npos) << cal.output;
  const lp::CameraResponse response = lp::CameraResponse::load(emu.tmp / "r.json");
  double logScale = 0;
  for (int code = 32; code <= 240; ++code)
    logScale +=
        std::log(response.linear[1][std::size_t(code)] / lp::srgbToLinear(code / 255.0f)) / 209;
  for (int c = 0; c < 3; ++c)
    for (int code = lp::kYuvTrustedFrom; code <= lp::kBrightestCode; ++code)
      EXPECT_NEAR(response.linear[std::size_t(c)][std::size_t(code)] / std::exp(logScale) /
                      lp::srgbToLinear(code / 255.0f),
                  1.0, 0.03)
          << "channel "
          << "RGB"[c] << ", code " << code;
}

// calibrate measures how many frames a camera takes to show a new exposure, with the metadata
// node and without it (from the frames' brightness), and writes it with the response; live,
// bracketing with that response, says in one warning when the camera it runs shows another
// delay (the run goes on: each frame is merged at the exposure it shows).
TEST(LiveHdr, TheControlDelayIsCalibratedAndCheckedLive) {
  for (const bool metadata : {true, false}) {
    Emulator emu("RGB3_256x128", {skyFrame(30)}, "control_delay=3");
    if (!metadata) emu.env = "LPEMU_META_DEVICE= ";
    const std::string r = emu.tmp / "r.json";
    const auto cal = emu.run("calibrate /dev/video7 --lock-exposure 0.3 --out " + r);
    ASSERT_EQ(cal.exitCode, 0) << cal.output;
    EXPECT_NE(cal.output.find("a new exposure shows 3 frames after it is asked"), std::string::npos)
        << cal.output;
    EXPECT_EQ(lp::CameraResponse::load(r).controlDelay, 3);
    for (const int delay : {3, 1}) {
      Emulator cam("RGB3_256x128", {skyFrame(30)}, "control_delay=" + std::to_string(delay));
      cam.env = emu.env;
      const auto live = cam.run("live /dev/video7" + kBracket + "--frames 12 --response " + r);
      ASSERT_EQ(live.exitCode, 0) << live.output;
      const std::string said = "warning: /dev/video7: a new exposure showed " +
                               std::to_string(delay) + " frame" + (delay == 1 ? "" : "s") +
                               " after it was asked; the calibration (--response) measured 3";
      if (delay == 3)
        EXPECT_EQ(live.output.find("a new exposure showed"), std::string::npos) << live.output;
      else
        EXPECT_NE(live.output.find(said), std::string::npos) << metadata << "\n" << live.output;
    }
  }
}

}  // namespace
