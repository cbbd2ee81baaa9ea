// Exposure bracketing's library parts against analytic truth: 8-bit frames rendered from a known
// radiance map through a known response merge back to that map; motion and a covered lens are
// caught; a response is recovered from a sweep; a UVC metadata buffer gives its exposure time.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>
#include <vector>

#include "liveprobe/backends.h"
#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/hdr/calibrate.h"
#include "liveprobe/hdr/exposure_estimate.h"
#include "liveprobe/hdr/merge.h"
#if LIVEPROBE_WITH_V4L2
#include <linux/uvcvideo.h>

#include "liveprobe/capture/v4l2.h"
#endif
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/projector.h"
#include "liveprobe/sh/simd.h"
#include "test_util.h"
#include "turned_map.h"
#include "yuyv.h"

namespace {

using lp::BracketMerger;
using lp::CameraResponse;
using lp::Frame;
using lp::FrameConfidence;
using lp::MergeOptions;

constexpr int kW = 128, kH = 64;

// Radiance (linear RGB, per second of exposure): a sky from 0.02 at the horizon to 0.2 at the
// zenith, a 2000x brighter sun (about 11 stops over the sky) in a 3-pixel disc, a dark ground.
std::vector<float> scene(int sunX = 40) {
  std::vector<float> rgb(std::size_t(kW) * kH * 3);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      float v = y < kH / 2 ? 0.02f + 0.18f * float(kH / 2 - y) / float(kH / 2) : 0.01f;
      if ((x - sunX) * (x - sunX) + (y - 12) * (y - 12) <= 2) v = 400.0f;
      float* p = &rgb[(std::size_t(y) * kW + x) * 3];
      p[0] = v, p[1] = 0.9f * v, p[2] = 0.8f * v;
    }
  return rgb;
}

// What an 8-bit camera with response `encode` (linear 0..1 to code 0..1) reads at exposure t.
template <class Encode>
Frame shoot(const std::vector<float>& radiance, double t, Encode encode) {
  Frame f;
  f.format = lp::PanoramaFormat::BgrU8;
  f.width = kW, f.height = kH;
  f.radianceScale = 1.0 / t;
  f.bgr8.resize(radiance.size());
  for (std::size_t i = 0; i < radiance.size(); i += 3)
    for (int c = 0; c < 3; ++c) {
      const float v = std::clamp(float(radiance[i + std::size_t(c)] * t), 0.0f, 1.0f);
      f.bgr8[i + 2 - std::size_t(c)] = std::uint8_t(std::lround(255.0f * encode(v)));
    }
  return f;
}

Frame shootSrgb(const std::vector<float>& radiance, double t) {
  return shoot(radiance, t, [](float v) { return lp::linearToSrgb(v); });
}

// The truth merged against: pixels some exposure read between codes 16 and 249.
double relativeError(float merged, float truth) { return std::abs(merged - truth) / truth; }

// Exposures told from the pixels alone (a camera without per-frame metadata), against frames
// shot at known times: the anchor at 1 s; 1/64 s shares well-measured sky with it and is
// measured by ratio; 1/4096 s reads only the sun and its glow, clipped in the others, and is
// named by what the known frames contradict least; a camera that rounded 1/64 to 1/60 is measured
// as 1/60; a frame half at one exposure and half at another (the sensor changing) agrees with none.
TEST(HdrMerge, ExposuresAreToldFromThePixels) {
  // The sky with the glow a real sun has around it (falling from 30 to the sky's level within
  // 10 pixels): the tones between the sky and the sun that tell 1/4096 s from 1/64 s.
  auto radiance = scene();
  for (int y = 0; y < kH / 2; ++y)
    for (int x = 0; x < kW; ++x) {
      const float d2 = float((x - 40) * (x - 40) + (y - 12) * (y - 12));
      for (int c = 0; c < 3; ++c)
        radiance[(std::size_t(y) * kW + x) * 3 + std::size_t(c)] += 30.0f * std::exp(-d2 / 20.0f);
    }
  const double base = 1.0, mid = 1.0 / 64, shortest = 1.0 / 4096;
  lp::ExposureIdentifier id({shortest, mid, base}, CameraResponse::srgb());
  EXPECT_FALSE(id.identify(shootSrgb(radiance, base)).has_value());  // nothing known yet
  id.seed(shootSrgb(radiance, base), base);
  for (int cycle = 0; cycle < 3; ++cycle)
    for (const double t : {shortest, mid, base}) {
      const auto told = id.identify(shootSrgb(radiance, t));
      ASSERT_TRUE(told.has_value()) << "t " << t << " cycle " << cycle;
      EXPECT_EQ(*told, t) << "cycle " << cycle;  // within the estimate's precision: as asked
    }
  const auto rounded = id.identify(shootSrgb(radiance, 1.0 / 60));
  ASSERT_TRUE(rounded.has_value());
  EXPECT_NEAR(*rounded, 1.0 / 60, 0.01 / 60);
  Frame torn = shootSrgb(radiance, 1.0 / 8);
  const Frame top = shootSrgb(radiance, base);
  std::copy(top.bgr8.begin(), top.bgr8.begin() + long(top.bgr8.size() / 2), torn.bgr8.begin());
  EXPECT_FALSE(id.identify(torn).has_value()) << id.lastEstimate();
  EXPECT_THROW(id.seed(top, 0.0), lp::Error);
}

TEST(HdrMerge, TwelveStopsOfRadianceComeBack) {
  const auto radiance = scene();
  BracketMerger merger(MergeOptions{});
  Frame out;
  FrameConfidence c;
  for (double t : {1.0 / 4096, 1.0 / 64, 1.0}) c = merger.add(shootSrgb(radiance, t), out);
  ASSERT_EQ(out.format, lp::PanoramaFormat::RgbF32);
  EXPECT_EQ(c.exposures, 3);
  EXPECT_TRUE(c.brightestMeasured);
  EXPECT_NEAR(c.clippedShare, 0.0, 1e-9);
  EXPECT_NEAR(c.agreement, 1.0, 1e-6);
  // Every sky pixel and the sun within the 8-bit step of the exposure that read it best.
  double worst = 0;
  for (std::size_t i = 0; i < radiance.size(); ++i)
    worst = std::max(worst, relativeError(out.rgb[i], radiance[i]));
  EXPECT_LT(worst, 0.03);
}

// Codes outside those a calibration read carry no weight: the same bracket with a response read
// only from code 100 up leaves the sky's darker readings out, and what no exposure read above
// code 100 counts as dark.
TEST(HdrMerge, CodesACalibrationNeverReadCarryNoWeight) {
  const auto radiance = scene();
  CameraResponse partial = CameraResponse::srgb();
  partial.readFrom = 100;
  FrameConfidence whole, part;
  Frame a, b;
  BracketMerger all(MergeOptions{}), some(MergeOptions{.response = partial});
  for (double t : {1.0 / 4096, 1.0 / 64, 1.0}) {
    whole = all.add(shootSrgb(radiance, t), a);
    part = some.add(shootSrgb(radiance, t), b);
  }
  EXPECT_EQ(some.options().noiseFloor, 99);
  EXPECT_EQ(whole.darkShare, 0.0);
  // The ground (code 25 at 1 s, the longest) and the sky below 0.127 (code 100 at 1 s) are read
  // by no counted code: over half the frame.
  EXPECT_GT(part.darkShare, 0.5);
  EXPECT_LT(part.darkShare, 0.9);
}

TEST(HdrMerge, ClippedEverywhereIsALowerBoundAndSaysSo) {
  const auto radiance = scene();
  BracketMerger merger(MergeOptions{.frames = 2});
  Frame out;
  FrameConfidence c;
  for (double t : {1.0 / 16, 1.0}) c = merger.add(shootSrgb(radiance, t), out);
  EXPECT_FALSE(c.brightestMeasured);
  // The sun holds most of the power; clipped at 1 / (1/16 s) = 16, its share is still a fifth.
  EXPECT_GT(c.clippedShare, 0.05);
  const std::size_t sun = (std::size_t(12) * kW + 40) * 3;
  EXPECT_NEAR(out.rgb[sun], 16.0f, 0.01f);
  EXPECT_LT(out.rgb[sun], radiance[sun]);
}

TEST(HdrMerge, AMovedSunComesFromTheNewestFrameOnly) {
  // The sun moves 20 pixels between the frames; the newest frame (short) sees it at x = 60.
  BracketMerger merger(MergeOptions{.frames = 3});
  Frame out;
  FrameConfidence c;
  c = merger.add(shootSrgb(scene(20), 1.0), out);
  c = merger.add(shootSrgb(scene(20), 1.0 / 64), out);
  c = merger.add(shootSrgb(scene(60), 1.0 / 4096), out);
  const auto truth = scene(60);
  const std::size_t now = (std::size_t(12) * kW + 60) * 3, before = (std::size_t(12) * kW + 20) * 3;
  EXPECT_LT(relativeError(out.rgb[now], truth[now]), 0.03);
  // No ghost at the old position: the newest frame reads dark there, which contradicts the
  // older frames' clipped sun; what they saw is counted as lost light.
  EXPECT_LT(out.rgb[before], 0.01f * truth[now]);
  EXPECT_LT(c.agreement, 0.9);
}

// Every SIMD path merges alike: vectors of 4, 8 or 16 pixels, rows that end part-way through a
// vector and through a block, readings that agree, disagree and cannot tell (a sun that moves
// and is clipped in some frames, a sky that brightens 10% between frames), against the scalar
// path, one pixel at a time.
TEST(HdrMerge, EverySimdPathMergesAlike) {
  constexpr int w = 125;  // neither a whole block (64) nor a whole vector of any path
  const std::string before = lp::simd::current();
  const auto crop = [&](Frame f) {
    for (int y = 0; y < kH; ++y)
      std::memmove(&f.bgr8[std::size_t(y) * w * 3], &f.bgr8[std::size_t(y) * kW * 3], w * 3);
    f.bgr8.resize(std::size_t(w) * kH * 3), f.width = w;
    return f;
  };
  // A still bracket first: each pixel of the crop merges as in the whole width, and none is dark
  // (the padding past a row's end adds no pixel to the sums).
  const auto still = scene();
  for (const std::string& path : lp::simd::available()) {
    lp::simd::select(path);
    BracketMerger whole(MergeOptions{.frames = 3}), part(MergeOptions{.frames = 3});
    Frame a, b;
    FrameConfidence c;
    for (const double t : {1.0, 1.0 / 64, 1.0 / 4096}) {
      whole.add(shootSrgb(still, t), a);
      c = part.add(crop(shootSrgb(still, t)), b);
    }
    EXPECT_EQ(c.darkShare, 0.0) << path;
    EXPECT_EQ(c.clippedShare, 0.0) << path;
    for (int y = 0; y < kH; ++y)
      for (int i = 0; i < w * 3; ++i)
        ASSERT_EQ(b.rgb[std::size_t(y * w * 3 + i)], a.rgb[std::size_t(y * kW * 3 + i)]) << path;
  }
  std::vector<Frame> frames;
  for (int i = 0; i < 5; ++i) {
    auto radiance = scene(30 + 7 * i);
    for (float& v : radiance) v *= 1.0f + 0.1f * float(i % 2);
    frames.push_back(crop(shootSrgb(radiance, std::array{1.0, 1.0 / 64, 1.0 / 4096}[i % 3])));
  }
  std::vector<std::vector<float>> merged;
  std::vector<FrameConfidence> said;
  for (const std::string& path : lp::simd::available()) {
    lp::simd::select(path);
    BracketMerger merger(MergeOptions{.frames = 3});
    Frame out;
    for (const Frame& f : frames) {
      said.push_back(merger.add(f, out));
      merged.push_back(out.rgb);
    }
  }
  lp::simd::select(before);
  ASSERT_GE(merged.size(), frames.size());
  for (std::size_t k = frames.size(); k < merged.size(); ++k) {
    const std::size_t ref = k % frames.size();
    for (std::size_t i = 0; i < merged[k].size(); ++i)
      ASSERT_NEAR(merged[k][i], merged[ref][i], 1e-5f * merged[ref][i] + 1e-9f)
          << "path " << k / frames.size() << " frame " << ref << " value " << i;
    EXPECT_NEAR(said[k].value(), said[ref].value(), 1e-6) << ref;
    EXPECT_NEAR(said[k].clippedShare, said[ref].clippedShare, 1e-6) << ref;
    EXPECT_NEAR(said[k].darkShare, said[ref].darkShare, 1e-9) << ref;
    EXPECT_EQ(said[k].brightestMeasured, said[ref].brightestMeasured) << ref;
  }
  // The run exercised what it is meant to: light found contradicted, and a clipped sun.
  EXPECT_TRUE(std::any_of(said.begin(), said.end(), [](auto& c) { return c.agreement < 0.99; }));
  EXPECT_TRUE(std::any_of(said.begin(), said.end(), [](auto& c) { return !c.brightestMeasured; }));
}

TEST(HdrMerge, ACoveredLensIsLeftOutOrFlagged) {
  const auto radiance = scene();
  Frame out;
  // A dark frame in the middle of a good bracket: its readings carry no weight, so the sun and
  // the sky merge right; but the sun rests on the oldest frame's reading, which the dark frame
  // contradicted and the newest (clipping it) cannot confirm: the confidence says so.
  {
    BracketMerger merger(MergeOptions{.frames = 3});
    Frame dark = shootSrgb(radiance, 1.0 / 64);
    std::fill(dark.bgr8.begin(), dark.bgr8.end(), std::uint8_t(2));
    merger.add(shootSrgb(radiance, 1.0 / 4096), out);
    const FrameConfidence covered = merger.add(dark, out);
    const FrameConfidence c = merger.add(shootSrgb(radiance, 1.0), out);
    EXPECT_LT(covered.value(), 0.5);
    EXPECT_LT(c.value(), 0.5) << c.agreement << " " << c.clippedShare << " " << c.darkShare;
    for (int y : {12, 20})
      for (int x : {40, 90}) {
        const std::size_t at = (std::size_t(y) * kW + std::size_t(x)) * 3;
        EXPECT_LT(relativeError(out.rgb[at], radiance[at]), 0.03) << x << "," << y;
      }
  }
  // The newest frame dark: nothing is measured, and the confidence says so.
  {
    BracketMerger merger(MergeOptions{.frames = 3});
    Frame dark = shootSrgb(radiance, 1.0);
    std::fill(dark.bgr8.begin(), dark.bgr8.end(), std::uint8_t(2));
    merger.add(shootSrgb(radiance, 1.0 / 4096), out);
    merger.add(shootSrgb(radiance, 1.0 / 64), out);
    const FrameConfidence c = merger.add(dark, out);
    EXPECT_LT(c.value(), 0.2);
  }
}

// A hand or a white card over the lens in the newest frame, whatever exposure it came at and
// whatever exposures the two frames before it had (a camera that applies its controls late
// repeats or skips stops), after a merge that measured the whole scene: the light measured a
// frame ago is gone or unmeasured, and the confidence says so.
TEST(HdrMerge, AnOccludedNewestFrameIsNeverTrusted) {
  const auto radiance = scene();
  const std::vector<double> bracket = {1.0 / 4096, 1.0 / 64, 1.0};
  for (const std::uint8_t code : {std::uint8_t(2), std::uint8_t(255)})
    for (std::size_t a = 0; a < 3; ++a)
      for (std::size_t b = 0; b < 3; ++b)
        for (std::size_t now = 0; now < 3; ++now) {
          BracketMerger merger(MergeOptions{.frames = 3});
          Frame out;
          for (auto t = bracket.rbegin(); t != bracket.rend(); ++t)
            merger.add(shootSrgb(radiance, *t), out);
          merger.add(shootSrgb(radiance, bracket[a]), out);
          merger.add(shootSrgb(radiance, bracket[b]), out);
          Frame covered = shootSrgb(radiance, bracket[now]);
          std::fill(covered.bgr8.begin(), covered.bgr8.end(), code);
          const FrameConfidence c = merger.add(covered, out);
          EXPECT_LT(c.value(), 0.5)
              << "code " << int(code) << ", exposures " << a << b << now << ": clipped "
              << c.clippedShare << ", dark " << c.darkShare << ", agreement " << c.agreement;
        }
}

TEST(HdrMerge, TheResponseRecoveredFromASweepIsThePowerLaw) {
  const auto radiance = scene();
  std::vector<Frame> frames;
  for (int stop = -6; stop <= 3; ++stop)
    frames.push_back(
        shoot(radiance, std::exp2(stop), [](float v) { return std::pow(v, 1 / 2.6f); }));
  const CameraResponse r = lp::calibrateResponse(frames);
  EXPECT_LT(r.firstDecrease(), 0);
  const lp::PowerLaw like = lp::fitPowerLaw([&](int i) { return r.linear[1][std::size_t(i)]; });
  EXPECT_NEAR(like.gamma, 2.6, 0.05);
  for (int code : {32, 64, 128, 200, 240})
    EXPECT_NEAR(r.linear[1][std::size_t(code)], std::pow(code / 255.0, 2.6),
                0.03 * std::pow(code / 255.0, 2.6))
        << "code " << code;
  // A scene that changes during the sweep (a light switched on: the sky twice as bright from the
  // fifth frame on) tells no one curve: refused, in one line.
  auto brighter = radiance;
  for (std::size_t i = 0; i < brighter.size() / 2; ++i) brighter[i] *= 2;
  for (int k = 4; k < int(frames.size()); ++k)
    frames[std::size_t(k)] =
        shoot(brighter, std::exp2(k - 6), [](float v) { return std::pow(v, 1 / 2.6f); });
  try {
    lp::calibrateResponse(frames);
    ADD_FAILURE() << "a changing scene was calibrated";
  } catch (const lp::Error& e) {
    EXPECT_NE(std::string(e.what()).find("moved during the sweep"), std::string::npos) << e.what();
  }
}

TEST(HdrMerge, AResponseFileIsCheckedWhole) {
  const std::string good = CameraResponse::gamma(2.2f).json();
  EXPECT_NEAR(CameraResponse::parse(good, "r.json").linear[0][128], std::pow(128 / 255.0, 2.2),
              1e-6);
  auto failsWith = [](const std::string& text, const std::string& says) {
    try {
      CameraResponse::parse(text, "r.json");
      ADD_FAILURE() << "accepted " << text.substr(0, 60);
    } catch (const lp::Error& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    }
  };
  failsWith("{}", "r.json: not a camera response");
  failsWith(R"({"response": [[1,2],[1,2],[1,2]]})", "256 values");
  auto falling = nlohmann::json::parse(good);
  falling["response"][0][3] = 0.0;  // red falls from code 2 to code 3
  failsWith(falling.dump(), "falls at code 3 of channel R");
  failsWith(R"({"response": 7})", "3 curves");
  // The codes a calibration read: kept through a file, and only a range of codes.
  CameraResponse read = CameraResponse::gamma(2.6f);
  read.readFrom = 5, read.readTo = 240;
  const CameraResponse back = CameraResponse::parse(read.json(), "r.json");
  EXPECT_EQ(back.readFrom, 5);
  EXPECT_EQ(back.readTo, 240);
  EXPECT_EQ(nlohmann::json::parse(good).count("read"), 0u);  // a whole curve says nothing
  for (const auto* range : {"[200, 100]", "[-1, 255]", "[0, 256]", "7"}) {
    auto bad = nlohmann::json::parse(good);
    bad["read"] = nlohmann::json::parse(range);
    failsWith(bad.dump(), "\"read\"");
  }
}

// One 8-bit frame: its clipped share is the power of the pixels with a channel at 255 over the
// map's, both by solid angle (here summed by hand over sin(theta) rows); float frames are
// trusted whole.
TEST(FrameConfidence, OneFramesClippedShareIsItsClippedPixelsPower) {
  Frame f;
  f.format = lp::PanoramaFormat::BgrU8;
  f.width = kW, f.height = kH;
  f.radianceScale = 4.0;
  f.bgr8.assign(std::size_t(kW) * kH * 3, 128);
  for (int y = 10; y < 14; ++y)
    for (int x = 30; x < 36; ++x) std::fill_n(&f.bgr8[(std::size_t(y) * kW + x) * 3], 3, 255);
  lp::FrameProcessor processor(lp::FrameProcessorOptions{});
  const lp::FrameLighting lit = processor.process(f);
  const FrameConfidence c = processor.confidence(f, lit);
  double clipped = 0, total = 0;
  for (int y = 0; y < kH; ++y) {
    const double w = std::sin(M_PI * (y + 0.5) / kH);
    for (int x = 0; x < kW; ++x) {
      const bool hot = y >= 10 && y < 14 && x >= 30 && x < 36;
      const double v = hot ? 1.0 : lp::srgbToLinear(128 / 255.0f);
      total += v * w;
      if (hot) clipped += v * w;
    }
  }
  EXPECT_NEAR(c.clippedShare, clipped / total, 1e-4);
  EXPECT_FALSE(c.brightestMeasured);
  Frame hdr;
  hdr.format = lp::PanoramaFormat::RgbF32;
  hdr.width = kW, hdr.height = kH;
  hdr.rgb.assign(std::size_t(kW) * kH * 3, 5.0f);
  const FrameConfidence h = processor.confidence(hdr, processor.process(hdr));
  EXPECT_EQ(h.clippedShare, 0.0);
  EXPECT_TRUE(h.brightestMeasured);
}

TEST(HdrMerge, OnlyBracketsOfEightBitFramesMerge) {
  BracketMerger merger(MergeOptions{});
  Frame f, out;
  f.format = lp::PanoramaFormat::RgbF32;
  f.width = 2, f.height = 1;
  f.rgb.assign(6, 1.0f);
  EXPECT_THROW(merger.add(f, out), lp::Error);
  EXPECT_THROW(BracketMerger(MergeOptions{.frames = 6}), lp::Error);
}

#if LIVEPROBE_WITH_V4L2
// One uvc_meta_buf block: ns, sof, then a payload header of `length` bytes.
std::vector<std::uint8_t> metaBlock(std::uint8_t flags, const std::vector<std::uint8_t>& rest) {
  uvc_meta_buf head{};
  head.ns = 123456789;
  head.sof = 42;
  head.length = std::uint8_t(2 + rest.size());
  head.flags = flags;
  std::vector<std::uint8_t> b(sizeof head + rest.size());
  std::memcpy(b.data(), &head, sizeof head);
  if (!rest.empty()) std::memcpy(b.data() + sizeof head, rest.data(), rest.size());
  return b;
}

// Microsoft's MetadataId_CaptureStats item: id 3, size, flags, reserved, ExposureTime (100 ns).
std::vector<std::uint8_t> captureStats(std::uint32_t flags, std::uint64_t exposure100ns) {
  std::vector<std::uint8_t> s(80, 0);
  const std::uint32_t id = 3, size = 80;
  std::memcpy(s.data(), &id, 4), std::memcpy(s.data() + 4, &size, 4);
  std::memcpy(s.data() + 8, &flags, 4), std::memcpy(s.data() + 16, &exposure100ns, 8);
  return s;
}

TEST(UvcMetadata, TheExposureTimeIsReadFromMicrosoftsCaptureStatistics) {
  std::vector<std::uint8_t> rest(4 + 6, 0);    // PTS and SCR
  const auto stats = captureStats(1, 333000);  // 33.3 ms
  rest.insert(rest.end(), stats.begin(), stats.end());
  // A header-only block first (as a frame's later packets give), then the one with statistics.
  const auto header = metaBlock(0x0c, std::vector<std::uint8_t>(10, 0));
  const auto block = metaBlock(0x8e, rest);
  std::vector<std::uint8_t> buffer(header.size() + block.size());
  std::memcpy(buffer.data(), header.data(), header.size());
  std::memcpy(buffer.data() + header.size(), block.data(), block.size());
  const auto t = lp::parseUvcExposure(buffer.data(), buffer.size());
  ASSERT_TRUE(t.has_value());
  EXPECT_NEAR(*t, 0.0333, 1e-9);
  // The exposure-time flag off, the standard header alone, or a torn block: no exposure.
  auto noFlag = metaBlock(0x8e, rest);
  noFlag[sizeof(uvc_meta_buf) + 10 + 8] = 0;
  EXPECT_FALSE(lp::parseUvcExposure(noFlag.data(), noFlag.size()));
  const auto plain = metaBlock(0x0c, std::vector<std::uint8_t>(10, 0));
  EXPECT_FALSE(lp::parseUvcExposure(plain.data(), plain.size()));
  EXPECT_FALSE(lp::parseUvcExposure(block.data(), block.size() - 30));
  EXPECT_FALSE(lp::parseUvcExposure(block.data(), 5));
}

TEST(UvcMetadata, TheMetadataNodeFollowsTheVideoNode) {
  EXPECT_EQ(lp::siblingMetadataNode("/dev/video0"), "/dev/video1");
  EXPECT_EQ(lp::siblingMetadataNode("/dev/video19"), "/dev/video20");
  EXPECT_EQ(lp::siblingMetadataNode("/dev/camera"), "");
}
#endif  // LIVEPROBE_WITH_V4L2

}  // namespace

namespace {

// One 8-bit sRGB frame of a float map at exposure t (the map is radiance per second).
Frame shootImage(const lp::Image& map, double t, std::uint64_t sequence) {
  Frame f;
  f.format = lp::PanoramaFormat::BgrU8;
  f.width = map.width, f.height = map.height;
  f.radianceScale = 1.0 / t;
  f.sequence = sequence;
  f.bgr8.resize(map.rgb.size());
  for (std::size_t i = 0; i < map.rgb.size(); i += 3)
    for (std::size_t c = 0; c < 3; ++c)
      f.bgr8[i + 2 - c] = std::uint8_t(std::lround(
          255.0f * lp::linearToSrgb(std::clamp(float(map.rgb[i + c] * t), 0.0f, 1.0f))));
  return f;
}

double sunShare(const float* rgb, int w, int h) {
  const lp::LightSplit s =
      lp::projectWithLights(lp::PanoramaView::rgbF32(rgb, w, h), lp::LightOptions{.maxLights = 1});
  return s.lights.empty() ? 0.0 : double(s.lights.front().share);
}

}  // namespace

// A camera turning 1 degree a frame (quarry_01, a sun over a quarry, at 256x128) about the
// vertical and about a tilted axis, bracketing -13, -7 and 0 EV: merged with its older frames
// turned to the newest by the rotation the frames show, the sun keeps its share of the HDR
// frame's in every frame past start-up; merged as they come, it does not.
TEST(HdrMerge, ATurningCamerasFramesAreAlignedBeforeTheyMerge) {
  const lp::Image full = lp::loadImage(lpt::dataPath("equirect/quarry_01_1k.hdr"));
  const lp::Image map = lp::reduceEquirect(full.rgb.data(), full.width, full.height, 4);
  std::vector<float> lum;
  for (std::size_t i = 0; i < map.rgb.size(); i += 3) lum.push_back(map.rgb[i + 1]);
  std::nth_element(lum.begin(), lum.begin() + lum.size() / 2, lum.end());
  const double t0 = 0.18 / lum[lum.size() / 2];  // 0 EV: the median at mid-grey
  const double yaw[3] = {0, 0, 1}, tilted[3] = {0.57735, 0.57735, 0.57735};
  for (const double* axis : {yaw, tilted})
    for (const bool align : {false, true}) {
      BracketMerger merger(MergeOptions{.frames = 3, .align = align});
      Frame out;
      int frames = 0, within = 0;
      std::string misses;
      for (int n = 0; n < 40; ++n) {
        const lp::Image now = lpt::turnedMap(map, axis, n);
        const int stop[3] = {-13, -7, 0};
        merger.add(shootImage(now, t0 * std::exp2(stop[n % 3]), std::uint64_t(n)), out);
        if (n < 6) continue;
        const double want = sunShare(now.rgb.data(), now.width, now.height);
        const double got = sunShare(out.rgb.data(), out.width, out.height);
        ++frames;
        if (std::abs(got - want) <= 0.1 * want)
          ++within;
        else
          misses += " " + std::to_string(n) + ":" + std::to_string(got / want);
      }
      std::printf("axis %g, %s: the share within 10%% in %d of %d frames;%s\n", axis[0],
                  align ? "aligned" : "as they come", within, frames, misses.c_str());
      if (align)
        EXPECT_GE(within, 0.95 * frames) << "axis " << axis[0] << misses;
      else
        EXPECT_LT(within, frames) << "axis " << axis[0] << ": the scene turns too little to tell";
    }
}

// A merge that projects as it goes gives the coefficients the projector gives of the frame it
// merged, on every SIMD path: a still bracket cropped to a width of no whole block or vector, and
// a turning camera whose older frames are turned before they merge; with the frame written and
// without, and the confidence the same.
TEST(HdrMerge, ProjectingAsItMergesGivesTheMergedFramesCoefficients) {
  const lp::Image full = lp::loadImage(lpt::dataPath("equirect/quarry_01_1k.hdr"));
  const lp::Image map = lp::reduceEquirect(full.rgb.data(), full.width, full.height, 4);
  const double axis[3] = {0.57735, 0.57735, 0.57735};
  std::vector<Frame> turning, still;
  for (int n = 0; n < 8; ++n)
    turning.push_back(shootImage(lpt::turnedMap(map, axis, 2 * n), 0.05 * std::exp2(-6 * (n % 3)),
                                 std::uint64_t(n)));
  constexpr int w = 125;
  for (int n = 0; n < 5; ++n) {
    Frame f = shootSrgb(scene(30 + 3 * n), std::array{1.0, 1.0 / 64, 1.0 / 4096}[n % 3]);
    for (int y = 0; y < kH; ++y)
      std::memmove(&f.bgr8[std::size_t(y) * w * 3], &f.bgr8[std::size_t(y) * kW * 3], w * 3);
    f.bgr8.resize(std::size_t(w) * kH * 3), f.width = w, f.sequence = std::uint64_t(n);
    still.push_back(std::move(f));
  }
  const std::string before = lp::simd::current();
  for (const std::string& path : lp::simd::available()) {
    lp::simd::select(path);
    for (const auto* frames : {&still, &turning}) {
      const lp::Projector projector(lp::Layout::Equirect, frames->front().width,
                                    frames->front().height);
      BracketMerger plain(MergeOptions{.frames = 3}), keeping(MergeOptions{.frames = 3}),
          projecting(MergeOptions{.frames = 3});
      Frame merged, kept, bare;
      for (const Frame& f : *frames) {
        const FrameConfidence c = plain.add(f, merged);
        lp::MergeProjection withFrame{.integrals = projector.equirectIntegrals()};
        lp::MergeProjection alone{.integrals = projector.equirectIntegrals(), .keepFrame = false};
        const FrameConfidence ck = keeping.add(f, kept, nullptr, withFrame);
        const FrameConfidence cb = projecting.add(f, bare, nullptr, alone);
        const std::string at = path + " frame " + std::to_string(f.sequence);
        ASSERT_EQ(kept.rgb, merged.rgb) << at;
        EXPECT_TRUE(bare.rgb.empty()) << at;
        EXPECT_EQ(bare.width, merged.width) << at;
        EXPECT_EQ(bare.captureTime, merged.captureTime) << at;
        for (const FrameConfidence& o : {ck, cb}) {
          EXPECT_EQ(o.value(), c.value()) << at;
          EXPECT_EQ(o.brightestMeasured, c.brightestMeasured) << at;
        }
        std::vector<float> peaks;
        const lp::Sh9 truth = projector.project(
            lp::PanoramaView::rgbF32(merged.rgb.data(), merged.width, merged.height), nullptr,
            &peaks);
        // The row peaks the projector finds in the merged frame, where a light search starts.
        EXPECT_EQ(withFrame.rowPeaks, peaks) << at;
        EXPECT_EQ(alone.rowPeaks, peaks) << at;
        const float l00 = std::max({truth.c[0].r, truth.c[0].g, truth.c[0].b});
        ASSERT_GT(l00, 0.0f) << at;
        for (int k = 0; k < lp::kShCount; ++k)
          for (int ch = 0; ch < 3; ++ch) {
            EXPECT_NEAR(withFrame.coefficients.c[k][ch], truth.c[k][ch], 1e-5f * l00)
                << at << " coefficient " << k << " channel " << ch;
            EXPECT_NEAR(alone.coefficients.c[k][ch], truth.c[k][ch], 1e-5f * l00)
                << at << " coefficient " << k << " channel " << ch;
          }
      }
    }
  }
  lp::simd::select(before);
  // A projection of another size is refused.
  const lp::Projector other(lp::Layout::Equirect, 64, 32);
  lp::MergeProjection wrong{.integrals = other.equirectIntegrals()};
  BracketMerger merger(MergeOptions{.frames = 3});
  Frame out;
  EXPECT_THROW(merger.add(still.front(), out, nullptr, wrong), lp::Error);
}

namespace {

// A sweep of one still sky (stops -12 to +3 about a mid-grey exposure) through a camera's
// response, as RGB24 or through YUYV (decoded as liveprobe decodes it).
std::vector<Frame> sweep(const lp::Image& sky, const std::function<double(double)>& encode,
                         bool yuyv) {
  std::vector<float> lum;
  for (std::size_t i = 0; i < sky.rgb.size(); i += 3) lum.push_back(sky.rgb[i + 1]);
  std::nth_element(lum.begin(), lum.begin() + std::ptrdiff_t(lum.size() / 2), lum.end());
  const double mid = 0.18 / lum[lum.size() / 2];
  std::vector<Frame> frames;
  for (int stop = -12; stop <= 3; ++stop) {
    const double t = mid * std::exp2(stop);
    cv::Mat bgr(sky.height, sky.width, CV_8UC3);
    for (int y = 0; y < sky.height; ++y)
      for (int x = 0; x < sky.width; ++x)
        for (int c = 0; c < 3; ++c) {
          const double v = std::clamp(
              double(sky.rgb[(std::size_t(y) * std::size_t(sky.width) + std::size_t(x)) * 3 +
                             std::size_t(c)]) *
                  t,
              0.0, 1.0);
          bgr.at<cv::Vec3b>(y, x)[2 - c] = std::uint8_t(std::lround(255.0 * encode(v)));
        }
    if (yuyv) {
      std::vector<std::uint8_t> sent = lpt::encodeYuyv(bgr);
      cv::cvtColor(cv::Mat(sky.height, sky.width, CV_8UC2, sent.data()), bgr,
                   cv::COLOR_YUV2BGR_YUYV);
    }
    Frame f;
    f.format = lp::PanoramaFormat::BgrU8;
    f.width = sky.width, f.height = sky.height;
    f.radianceScale = 1.0 / t;
    f.bgr8.assign(bgr.data, bgr.data + bgr.total() * 3);
    frames.push_back(std::move(f));
  }
  return frames;
}

// The worst relative error of a recovered curve (linear per code, R G B) over codes
// kDarkestCode..kBrightestCode in any channel, after the one scale a response leaves open
// (fitted to green over codes 32-240); `within3` gets the lowest code from which every code up to
// kBrightestCode is within 3%.
double worstError(const std::function<double(int c, int code)>& recovered,
                  const std::function<double(double)>& encode, int* within3 = nullptr) {
  std::array<double, 256> truth{};  // the inverse of `encode` at each code
  for (int code = 1; code < 256; ++code) {
    double lo = 0, hi = 1;
    for (int i = 0; i < 60; ++i)
      ((encode(0.5 * (lo + hi)) < code / 255.0) ? lo : hi) = 0.5 * (lo + hi);
    truth[std::size_t(code)] = 0.5 * (lo + hi);
  }
  double logScale = 0;
  for (int code = 32; code <= 240; ++code)
    logScale += std::log(recovered(1, code) / truth[std::size_t(code)]) / 209;
  double worst = 0;
  if (within3) *within3 = lp::kDarkestCode;
  for (int c = 0; c < 3; ++c)
    for (int code = lp::kDarkestCode; code <= lp::kBrightestCode; ++code) {
      const double e =
          std::abs(recovered(c, code) / std::exp(logScale) / truth[std::size_t(code)] - 1);
      worst = std::max(worst, e);
      if (within3 && e > 0.03) *within3 = std::max(*within3, code + 1);
    }
  return worst;
}

}  // namespace

// liveprobe's response recovery against OpenCV's photo module (Debevec and Malik's
// CalibrateDebevec, Robertson's CalibrateRobertson) on the same frames of a real scene (the quarry)
// through three cameras' curves, as RGB24 and through YUYV: the worst code 4-250 of each against
// the true curve. Ours is within 3% through RGB24, from code lp::kYuvTrustedFrom up through YUYV,
// and nearer the truth than either of OpenCV's on every camera and format (the table in hdr.md).
TEST(HdrMerge, TheResponseRecoveryAgainstOpenCvs) {
  const lp::Image full = lp::loadImage(lpt::dataPath("equirect/quarry_01_1k.hdr"));
  const lp::Image sky = lp::reduceEquirect(full.rgb.data(), full.width, full.height, 4);
  for (const auto& [name, encode] :
       std::vector<std::pair<std::string, std::function<double(double)>>>{
           {"sRGB", [](double v) { return double(lp::linearToSrgb(float(v))); }},
           {"gamma 1.8", [](double v) { return std::pow(v, 1 / 1.8); }},
           {"gamma 2.6", [](double v) { return std::pow(v, 1 / 2.6); }}})
    for (const bool yuyv : {false, true}) {
      const std::vector<Frame> frames = sweep(sky, encode, yuyv);
      const CameraResponse ours =
          lp::calibrateResponse(frames, yuyv ? lp::ChromaBlock{2, 1} : lp::ChromaBlock{});
      int from = 0;
      const double oursWorst = worstError(
          [&](int c, int z) { return ours.linear[std::size_t(c)][std::size_t(z)]; }, encode, &from);
      std::vector<cv::Mat> images;
      std::vector<float> times;
      for (const Frame& f : frames) {
        images.push_back(
            cv::Mat(f.height, f.width, CV_8UC3, const_cast<std::uint8_t*>(f.bgr8.data())));
        times.push_back(float(1.0 / f.radianceScale));
      }
      std::map<std::string, double> theirs;
      for (const auto& [method, calibrate] :
           std::vector<std::pair<std::string, cv::Ptr<cv::CalibrateCRF>>>{
               {"Debevec", cv::createCalibrateDebevec()},
               {"Robertson", cv::createCalibrateRobertson()}}) {
        cv::Mat crf;  // 256x1 CV_32FC3, B G R
        calibrate->process(images, crf, times);
        theirs[method] =
            worstError([&](int c, int z) { return double(crf.at<cv::Vec3f>(z)[2 - c]); }, encode);
      }
      if (yuyv)
        EXPECT_LE(from, lp::kYuvTrustedFrom) << name;
      else
        EXPECT_LE(oursWorst, 0.03) << name;
      EXPECT_LT(oursWorst, std::min(theirs["Debevec"], theirs["Robertson"])) << name;
      std::printf("%-10s %-6s within 3%% from %d; ours %.1f%%  Debevec %.1f%%  Robertson %.1f%%\n",
                  name.c_str(), yuyv ? "YUYV" : "RGB24", from, 100 * oursWorst,
                  100 * theirs["Debevec"], 100 * theirs["Robertson"]);
    }
}
