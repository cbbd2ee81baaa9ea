// The stream side of capture: SH rotation, smoothing, the latest-value handoff, sources.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <numbers>
#include <random>
#include <thread>

#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/capture/open_source.h"
#include "liveprobe/capture/pipeline.h"
#include "liveprobe/capture/recorder.h"
#include "liveprobe/capture/resample.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/hdr/bracketed_source.h"
#include "liveprobe/hdr/merge.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/executor.h"
#include "liveprobe/sh/projector.h"
#include "test_util.h"

namespace {

constexpr double kPi = std::numbers::pi;

// Rotating the coefficients equals projecting the rotated panorama (resampled here), within
// 0.5% of L00.
// The one frame path against the core's projection of the frame's linear radiance, computed here
// without it: the exposure (the photometry's and the frame's own) is applied exactly once for
// 8-bit and float frames alike, a reduction projects the area average, the orientation turns
// the result as rotateSh does, and with lights the rest plus the lights is the whole map.
TEST(FrameProcessor, OneExposureOneProjectionEveryFormat) {
  constexpr int w = 128, h = 64;
  std::vector<float> sky;
  lp::renderSyntheticSky(w, h, 0.7, sky);
  lp::Frame hdr;
  hdr.format = lp::PanoramaFormat::RgbF32;
  hdr.width = w, hdr.height = h;
  hdr.rgb = sky;
  hdr.radianceScale = 3.0;
  lp::Frame ldr;
  ldr.format = lp::PanoramaFormat::BgrU8;
  ldr.width = w, ldr.height = h;
  ldr.bgr8.resize(std::size_t(w) * h * 3);
  for (std::size_t p = 0; p < std::size_t(w) * h; ++p)
    for (int c = 0; c < 3; ++c)
      ldr.bgr8[3 * p + 2 - std::size_t(c)] =
          std::uint8_t(std::lround(255 * lp::linearToSrgb(std::min(1.0f, sky[3 * p + c] * 0.1f))));
  ldr.radianceScale = 3.0;
  const lp::Photometry photometry{.gamma = 0.0f, .exposure = 2.0f};
  for (const lp::Frame* frame : {&hdr, &ldr}) {
    // The truth: the frame's linear radiance (sRGB decoded in double), times 2 x 3, projected.
    lp::Image linear(w, h);
    for (std::size_t i = 0; i < linear.rgb.size(); ++i) {
      double v = frame == &hdr ? double(sky[i]) : 0.0;
      if (frame == &ldr) {
        const double code = ldr.bgr8[3 * (i / 3) + 2 - i % 3] / 255.0;
        v = code <= 0.04045 ? code / 12.92 : std::pow((code + 0.055) / 1.055, 2.4);
      }
      linear.rgb[i] = float(v * 6.0);
    }
    const lp::Sh9 truth = lp::project(lp::PanoramaView::rgbF32(linear.rgb.data(), w, h));
    lp::FrameProcessor plain({lp::LayoutSpec(), photometry, std::nullopt, 1, {.maxLights = 0}});
    const lp::FrameLighting lit = plain.process(*frame);
    for (int k = 0; k < lp::kShCount; ++k)
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(lit.radiance.c[k][c], truth.c[k][c], 2e-5 * truth.c[0][c] + 1e-6)
            << (frame == &hdr ? "float" : "8-bit") << " coefficient " << k;
    EXPECT_EQ(lit.whole, lit.radiance);
    EXPECT_TRUE(lit.lights.empty());

    const lp::Image small = lp::reduceEquirect(linear.rgb.data(), w, h, 4);
    const lp::Sh9 reducedTruth =
        lp::project(lp::PanoramaView::rgbF32(small.rgb.data(), small.width, small.height));
    lp::FrameProcessor reduced({lp::LayoutSpec(), photometry, std::nullopt, 4, {.maxLights = 0}});
    const lp::Sh9 r = reduced.process(*frame).radiance;
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(r.c[0][c], reducedTruth.c[0][c], 2e-5 * reducedTruth.c[0][c]);

    const glm::mat3 turn = lp::rotationYawPitchRoll(30.0f, -20.0f, 10.0f);
    lp::FrameProcessor turned({lp::LayoutSpec(), photometry, turn, 1, {.maxLights = 0}});
    const lp::Sh9 t = turned.process(*frame).radiance, want = lp::rotateSh(truth, turn);
    for (int k = 0; k < lp::kShCount; ++k)
      EXPECT_NEAR(t.c[k][1], want.c[k][1], 2e-5 * truth.c[0][1] + 1e-6) << "turned " << k;

    // The coefficients projected elsewhere (the GPU's way in: given the frame as the projection
    // reads it, here projected by the test itself) are scaled and turned as the CPU's: the same
    // truth; and so are the coefficients of the frame's own pixels handed in (a merge's way in).
    const auto shared = std::make_shared<lp::Frame>(*frame);
    int calls = 0;
    const lp::FrameResult elsewhere =
        turned.run(shared, {.projectWith = [&](const lp::ProjectionJob& job) {
                     ++calls;
                     EXPECT_EQ(job.rowPeaks, nullptr) << "no lights asked for";
                     return job.tables.project(job.view);
                   }});
    EXPECT_EQ(calls, 1);
    EXPECT_EQ(elsewhere.projectedOn, lp::ProjectedOn::Gpu);
    // (An 8-bit frame's own pixels are read through its table, which carries the exposure 2.)
    lp::Sh9 own = truth;
    own *= frame == &hdr ? 1.0f / 6.0f : 1.0f / 3.0f;
    const lp::FrameResult merged = turned.run(shared, {.projected = own});
    for (int k = 0; k < lp::kShCount; ++k) {
      EXPECT_NEAR(elsewhere.lighting.radiance.c[k][1], want.c[k][1], 2e-5 * truth.c[0][1] + 1e-6)
          << "projected elsewhere " << k;
      EXPECT_NEAR(merged.lighting.radiance.c[k][1], want.c[k][1], 2e-5 * truth.c[0][1] + 1e-6)
          << "projected as it was made " << k;
    }
    // Lights are searched in the frame's pixels: not with a merge's coefficients alone, and
    // with a projection of the caller's from the row peaks it gives (here the CPU's own, so
    // the lights are the CPU path's exactly).
    lp::FrameProcessor withSun({lp::LayoutSpec(), photometry, std::nullopt, 1, {.maxLights = 1}});
    EXPECT_THROW(withSun.run(shared, {.projected = own}), lp::Error);
    lp::FrameProcessor withSunElsewhere(
        {lp::LayoutSpec(), photometry, std::nullopt, 1, {.maxLights = 1}});
    lp::Sh9 projectedThere;
    std::vector<float> peaksThere;
    const lp::FrameResult sunElsewhere =
        withSunElsewhere.run(shared, {.projectWith = [&](const lp::ProjectionJob& job) {
                               EXPECT_NE(job.rowPeaks, nullptr);
                               projectedThere = job.tables.project(job.view, nullptr, job.rowPeaks);
                               peaksThere = *job.rowPeaks;
                               return projectedThere;
                             }});
    // Projected as it was made, with its row peaks (a merge's, projecting as it merges): the
    // light search reads the frame here, the same lights.
    lp::FrameProcessor withSunMade(
        {lp::LayoutSpec(), photometry, std::nullopt, 1, {.maxLights = 1}});
    const lp::FrameResult sunMade =
        withSunMade.run(shared, {.projected = projectedThere, .projectedPeaks = &peaksThere});
    const lp::FrameLighting s = withSun.process(*frame);
    ASSERT_EQ(s.lights.size(), 1u);
    ASSERT_EQ(sunElsewhere.lighting.lights.size(), 1u);
    EXPECT_EQ(sunElsewhere.lighting.lights[0].dir, s.lights[0].dir);
    EXPECT_EQ(sunElsewhere.lighting.lights[0].power, s.lights[0].power);
    ASSERT_EQ(sunMade.lighting.lights.size(), 1u);
    EXPECT_EQ(sunMade.lighting.lights[0].dir, s.lights[0].dir);
    EXPECT_EQ(sunMade.lighting.lights[0].power, s.lights[0].power);
    for (int k = 0; k < lp::kShCount; ++k)
      EXPECT_EQ(sunMade.lighting.radiance.c[k], s.radiance.c[k]) << "coefficient " << k;
    const lp::Sh9 sum = s.radiance + lp::lightsToSh(s.lights);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum.c[0][c], truth.c[0][c], 1e-4 * truth.c[0][c]);
  }
  lp::FrameProcessor angular({lp::LayoutSpec(lp::Layout::Angular), photometry});
  EXPECT_THROW(angular.process(hdr), lp::Error);  // a 2:1 frame is no angular map
}

// Sources describe their rate as a person writes it.
TEST(Sources, FrameRatesAsAPersonWritesThem) {
  EXPECT_EQ(lp::formatFps(30), "30 fps");
  EXPECT_EQ(lp::formatFps(30000.0 / 1001), "29.97 fps");
  EXPECT_EQ(lp::formatFps(25.126), "25.13 fps");
  EXPECT_EQ(lp::formatFps(0.5), "0.5 fps");
  EXPECT_EQ(lp::openSource("synthetic:64x32@29.97")->describe(), "synthetic sky 64x32 @ 29.97 fps");
}

TEST(ShRotation, EqualsProjectingTheRotatedPanorama) {
  const lp::Image eq = lp::loadImage(lpt::dataPath("probes/latlong_full/grace_latlong.exr"));
  const lp::Sh9 L = lp::project(lp::PanoramaView::rgbF32(eq.rgb.data(), eq.width, eq.height));
  for (auto [y, p, r] : {std::tuple{30.0f, 0.0f, 0.0f}, std::tuple{-70.0f, 25.0f, 10.0f},
                         std::tuple{120.0f, -40.0f, 75.0f}}) {
    const glm::mat3 R = lp::rotationYawPitchRoll(y, p, r);
    const glm::mat3 Rt = glm::transpose(R);
    // Rotated panorama: L'(w) = L(R^T w), nearest-neighbour lookups at 4x4 sub-pixel points.
    lp::Image rot(eq.width / 2, eq.height / 2);
    for (int i = 0; i < rot.height; ++i)
      for (int j = 0; j < rot.width; ++j) {
        glm::dvec3 acc(0);
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b) {
            const double t = kPi * (i + (a + 0.5) / 4) / rot.height,
                         ph = 2 * kPi * (j + (b + 0.5) / 4) / rot.width;
            const glm::vec3 w(std::sin(t) * std::cos(ph), std::sin(t) * std::sin(ph), std::cos(t));
            const glm::vec3 s = Rt * w;
            double sp = std::atan2(s.y, s.x);
            if (sp < 0) sp += 2 * kPi;
            const int sx = std::min(eq.width - 1, int(sp / (2 * kPi) * eq.width));
            const int sy =
                std::min(eq.height - 1,
                         int(std::acos(std::clamp(double(s.z), -1.0, 1.0)) / kPi * eq.height));
            const float* v = eq.pixel(sx, sy);
            acc += glm::dvec3(v[0], v[1], v[2]);
          }
        acc /= 16.0;
        float* o = rot.pixel(j, i);
        o[0] = float(acc.x), o[1] = float(acc.y), o[2] = float(acc.z);
      }
    const lp::Sh9 a = lp::project(lp::PanoramaView::rgbF32(rot.rgb.data(), rot.width, rot.height));
    const lp::Sh9 b = lp::rotateSh(L, R);
    for (int k = 0; k < 9; ++k)
      for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(b.c[k][ch], a.c[k][ch], 0.005 * a.c[0][ch]) << lp::kShNames[k] << " yaw " << y;
  }
}

TEST(ShRotation, BasicAxes) {
  // Yaw 90 degrees turns a light at +x to +y.
  lp::Sh9 L;
  const auto y = lp::shBasis({1, 0, 0});
  for (int k = 0; k < 9; ++k) L.c[k] = glm::vec3(y[k]);
  const lp::Sh9 r = lp::rotateSh(L, lp::rotationYawPitchRoll(90, 0, 0));
  const auto want = lp::shBasis({0, 1, 0});
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(r.c[k].x, want[k], 1e-5) << lp::kShNames[k];
}

// What the constant band-2 rotation rests on: the icosahedron's vertices integrate the products
// of band-2 basis functions exactly, sum_i Y2a Y2b = (12 / 4 pi) delta_ab (here to the six digits
// of the basis constants).
TEST(ShRotation, IcosahedronIsABand2Design) {
  const auto& d = lp::band2Design();
  for (int a = 0; a < 5; ++a)
    for (int b = 0; b < 5; ++b) {
      double sum = 0;
      for (int i = 0; i < 12; ++i) sum += d.basis[i][a] * d.basis[i][b];
      EXPECT_NEAR(sum, a == b ? 12 / (4 * M_PI) : 0.0, 1e-5) << a << " " << b;
    }
}

// Rotations compose (R2 after R1 is R2 R1), keep each band's norm, and undo each other; a
// reflection applied twice is the identity. Random coefficients, random rotations.
TEST(ShRotation, ComposesAndKeepsBandNorms) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1, 1), deg(-180, 180);
  auto bandNorm = [](const lp::Sh9& L, int lo, int hi, int ch) {
    double s = 0;
    for (int k = lo; k < hi; ++k) s += double(L.c[k][ch]) * L.c[k][ch];
    return std::sqrt(s);
  };
  for (int trial = 0; trial < 20; ++trial) {
    lp::Sh9 L;
    for (auto& c : L.c) c = {u(rng), u(rng), u(rng)};
    const glm::mat3 r1 = lp::rotationYawPitchRoll(deg(rng), deg(rng), deg(rng)),
                    r2 = lp::rotationYawPitchRoll(deg(rng), deg(rng), deg(rng));
    const lp::Sh9 a = lp::rotateSh(lp::rotateSh(L, r1), r2), b = lp::rotateSh(L, r2 * r1);
    const lp::Sh9 back = lp::rotateSh(lp::rotateSh(L, r1), glm::transpose(r1));
    const glm::mat3 flip(glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, 0, -1));
    const lp::Sh9 twice = lp::rotateSh(lp::rotateSh(L, flip), flip);
    for (int k = 0; k < 9; ++k)
      for (int ch = 0; ch < 3; ++ch) {
        EXPECT_NEAR(a.c[k][ch], b.c[k][ch], 1e-5);
        EXPECT_NEAR(back.c[k][ch], L.c[k][ch], 1e-5);
        EXPECT_NEAR(twice.c[k][ch], L.c[k][ch], 1e-6);
      }
    for (int ch = 0; ch < 3; ++ch) {
      EXPECT_NEAR(bandNorm(b, 1, 4, ch), bandNorm(L, 1, 4, ch), 1e-5);
      EXPECT_NEAR(bandNorm(b, 4, 9, ch), bandNorm(L, 4, 9, ch), 1e-5);
    }
  }
}

// The EMA of coefficients equals the projection of the EMA of frames (SH is linear), and a step
// reaches 63% after tau.
TEST(Smoothing, ExactAndLatency) {
  lp::ShSmoother sm(0.5);
  lp::Sh9 zero, one;
  one.c[0] = glm::vec3(1.0f);
  sm.update(zero, 0.0);
  lp::Sh9 out;
  for (int i = 1; i <= 50; ++i) out = sm.update(one, i * 0.01);  // 0.5 s after the step
  EXPECT_NEAR(out.c[0].x, 1 - std::exp(-1.0), 1e-4);
}

// A slow renderer never slows capture: a 200 fps synthetic stream paced in real time keeps its
// rate while the consumer takes a frame every 50 ms; the rest are dropped and counted.
TEST(Handoff, SlowRendererDoesNotBlockCapture) {
  lp::PipelineOptions opt;
  opt.handoff = lp::Handoff::Latest;
  opt.realtime = true;
  opt.maxFrames = 200;  // one second
  opt.keepImages = false;
  lp::CapturePipeline pipe(lp::openSource("synthetic:64x32@200"), opt);
  const auto t0 = std::chrono::steady_clock::now();
  pipe.start();
  int taken = 0;
  while (!pipe.finished()) {
    if (pipe.takeLatest()) ++taken;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the "renderer"
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  pipe.stop();
  const auto st = pipe.stats();
  EXPECT_EQ(st.captured, 200u);
  EXPECT_LT(s, 1.3) << "capture was slowed down by the renderer";
  EXPECT_LE(taken, 25);
  EXPECT_GE(st.dropped, 170u);
  EXPECT_EQ(st.taken, std::size_t(taken));
  EXPECT_LE(st.captured - st.dropped - st.taken,
            1u);  // at most the last frame is still in the slot
}

// Handoff::Every hands over every frame, in order.
TEST(Handoff, EveryFrameWhenAsked) {
  lp::PipelineOptions opt;
  opt.handoff = lp::Handoff::Every;
  opt.maxFrames = 20;
  lp::CapturePipeline pipe(lp::openSource("synthetic:32x16@30"), opt);
  pipe.start();
  std::uint64_t expect = 0;
  while (auto f = pipe.waitNext()) {
    EXPECT_EQ(f->index, expect++);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(expect, 20u);
  EXPECT_EQ(pipe.stats().dropped, 0u);
}

// A projection of the caller's (the GPU's way in, PipelineOptions::projectOnGpu): made once on
// the capture thread, used and destroyed there, every frame projected by it (said per frame and
// counted), the coefficients those of the CPU's projection (here the job's own tables).
TEST(Handoff, AProjectionOfTheCallersIsMadeUsedAndDroppedOnTheCaptureThread) {
  lp::PipelineOptions opt;
  opt.handoff = lp::Handoff::Every;
  opt.maxFrames = 5;
  std::vector<std::thread::id> madeOn, usedOn, droppedOn;
  struct Dropped {
    std::vector<std::thread::id>* on = nullptr;
    ~Dropped() {
      if (on) on->push_back(std::this_thread::get_id());
    }
  };
  opt.projectOnGpu = [&] {
    madeOn.push_back(std::this_thread::get_id());
    auto dropped = std::make_shared<Dropped>();
    dropped->on = &droppedOn;
    lp::GpuWork work;
    work.project = [&, dropped](const lp::ProjectionJob& job) {
      usedOn.push_back(std::this_thread::get_id());
      return job.tables.project(job.view);
    };
    return work;
  };
  lp::PipelineOptions cpuOpt = opt;
  cpuOpt.projectOnGpu = nullptr;
  lp::CapturePipeline pipe(lp::openSource("synthetic:64x32@30"), opt);
  lp::CapturePipeline cpu(lp::openSource("synthetic:64x32@30"), cpuOpt);
  pipe.start();
  cpu.start();
  while (auto f = pipe.waitNext()) {
    const auto c = cpu.waitNext();
    ASSERT_TRUE(c);
    EXPECT_EQ(f->projectedOn, lp::ProjectedOn::Gpu);
    EXPECT_EQ(c->projectedOn, lp::ProjectedOn::Cpu);
    for (int k = 0; k < lp::kShCount; ++k)
      EXPECT_NEAR(f->radiance.c[k][1], c->radiance.c[k][1], 1e-6f * c->radiance.c[0][1]) << k;
  }
  pipe.stop();
  cpu.stop();
  EXPECT_EQ(pipe.stats().projectedOnGpu, 5u);
  EXPECT_EQ(cpu.stats().projectedOnGpu, 0u);
  ASSERT_EQ(madeOn.size(), 1u);
  ASSERT_EQ(usedOn.size(), 5u);
  ASSERT_EQ(droppedOn.size(), 1u);
  EXPECT_NE(madeOn[0], std::this_thread::get_id());
  for (const auto& id : usedOn) EXPECT_EQ(id, madeOn[0]);
  EXPECT_EQ(droppedOn[0], madeOn[0]);
}

TEST(Handoff, LayoutMismatchStopsWithAClearError) {
  lp::PipelineOptions opt;
  opt.layout = lp::Layout::Angular;
  opt.handoff = lp::Handoff::Every;
  lp::CapturePipeline pipe(lp::openSource("synthetic:64x32@30"), opt);
  pipe.start();
  EXPECT_FALSE(pipe.waitNext().has_value());
  EXPECT_NE(pipe.stats().error.find("must be square"), std::string::npos) << pipe.stats().error;
}

// The background is made in one place: what the capture pipeline hands the viewer is
// FrameProcessor::run's, byte for byte, for an 8-bit frame the display decodes (equirect and
// angular: the frame itself, shared), an 8-bit cube (its linear copy resampled to equirect) and
// float maps (a linear copy, scaled by the frame's exposure, and resampled where GL does not draw
// the layout).
TEST(Background, ThePipelineDrawsFrameProcessorRunsBackground) {
  lpt::TempDir tmp;
  std::vector<std::uint8_t> rgb(64 * 32 * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = std::uint8_t((i * 37) % 256);
  const std::string png = tmp / "pano.png", square = tmp / "angular.png";
  lp::saveRgb8(png, 64, 32, rgb.data());
  lp::saveRgb8(square, 32, 32, rgb.data());
  const std::string data = LIVEPROBE_DATA_DIR;
  const std::vector<std::pair<std::string, lp::LayoutSpec>> cases = {
      {png, lp::LayoutSpec(lp::Layout::Equirect)},
      {square, lp::LayoutSpec(lp::Layout::Angular)},
      {data + "/probes/latlong_256x128/grace.hdr", lp::LayoutSpec(lp::Layout::Equirect)},
      {data + "/cube/pisaHDR", lp::LayoutSpec(lp::Layout::Cube)},
  };
  for (const auto& [file, layout] : cases) {
    SCOPED_TRACE(file);
    lp::PipelineOptions opt;
    opt.layout = layout;
    opt.handoff = lp::Handoff::Every;
    opt.maxFrames = 1;
    opt.keepImages = true;
    lp::CapturePipeline pipe(lp::openSource(file), opt);
    pipe.start();
    const auto shown = pipe.waitNext();
    ASSERT_TRUE(shown.has_value()) << pipe.stats().error;
    const lp::Background& a = shown->background;
    auto frame = std::make_shared<lp::Frame>();
    ASSERT_TRUE(lp::openSource(file)->next(*frame));
    lp::FrameProcessor processor({layout, opt.photometry, std::nullopt, 1, {.maxLights = 0}});
    const lp::Background b = processor.run(frame, {.background = true}).background;
    const bool asIs =
        frame->format == lp::PanoramaFormat::BgrU8 && layout.layout != lp::Layout::Cube;
    ASSERT_EQ(bool(a.raw), asIs);
    ASSERT_EQ(bool(b.raw), asIs);
    EXPECT_EQ(a.layout, b.layout);
    EXPECT_EQ(a.layout,
              layout.layout == lp::Layout::Angular ? lp::Layout::Angular : lp::Layout::Equirect);
    EXPECT_EQ(a.scale, b.scale);
    if (asIs) {
      EXPECT_EQ(a.raw->bgr8, b.raw->bgr8);
      EXPECT_EQ(b.raw.get(), frame.get()) << "the frame is shared, not copied";
    } else {
      ASSERT_TRUE(a.image && b.image);
      EXPECT_EQ(a.image->width, b.image->width);
      EXPECT_EQ(a.image->height, b.image->height);
      EXPECT_EQ(a.image->rgb, b.image->rgb);
      EXPECT_EQ(a.image->width, 2 * a.image->height) << "drawn as equirect";
    }
  }
}

// A bracketing camera's frames, shot here from a float map at three exposures through the sRGB
// curve, each with its exposure (Frame::radianceScale = 1 / t).
class BracketSource : public lp::FrameSource, public lp::BracketedSource {
 public:
  explicit BracketSource(const lp::Image& map) {
    for (int n = 0; n < 7; ++n) {
      const double t = 0.5 * std::exp2(-6.0 * (n % 3));
      lp::Frame f;
      f.format = lp::PanoramaFormat::BgrU8;
      f.width = map.width, f.height = map.height;
      f.radianceScale = 1.0 / t;
      f.sequence = std::uint64_t(n), f.timestamp = n / 30.0;
      f.bgr8.resize(map.rgb.size());
      for (std::size_t i = 0; i < map.rgb.size(); i += 3)
        for (std::size_t c = 0; c < 3; ++c)
          f.bgr8[i + 2 - c] = std::uint8_t(std::lround(
              255.0f * lp::linearToSrgb(std::clamp(float(map.rgb[i + c] * t), 0.0f, 1.0f))));
      frames_.push_back(std::move(f));
    }
  }
  bool next(lp::Frame& frame) override {
    if (at_ == frames_.size()) return false;
    frame = frames_[at_++];
    return true;
  }
  bool rewind() override { return at_ = 0, true; }
  std::string describe() const override { return "bracket"; }
  double fps() const override { return 30; }
  int bracketFrames() const override { return 3; }
  const std::vector<lp::Frame>& frames() const { return frames_; }

 private:
  std::vector<lp::Frame> frames_;
  std::size_t at_ = 0;
};

// A bracket merged and projected in one pass, in the pipeline, with the float frame written
// (a display) and without: each frame's coefficients are those of the merged frame projected
// through the one frame path (exposure and orientation applied once), and the display's
// background is the merged frame.
TEST(Bracket, ThePipelinesOnePassIsTheMergedFrameProjected) {
  const lp::Image map = lp::loadImage(lpt::dataPath("probes/latlong_256x128/grace.hdr"));
  const BracketSource shots(map);
  const lp::Photometry photometry{.exposure = 2.0f};
  const glm::mat3 turn = lp::rotationYawPitchRoll(10, 20, 30);
  std::vector<lp::Sh9> truth;
  {
    lp::BracketMerger merger(lp::MergeOptions{.frames = 3});
    lp::FrameProcessor processor(
        {lp::LayoutSpec(lp::Layout::Equirect), photometry, turn, 1, {.maxLights = 0}});
    lp::Frame merged;
    for (const lp::Frame& f : shots.frames()) {
      merger.add(f, merged);
      truth.push_back(processor.process(merged).radiance);
    }
  }
  for (const bool keepImages : {false, true}) {
    SCOPED_TRACE(keepImages ? "with the frame" : "without the frame");
    lp::PipelineOptions opt;
    opt.layout = lp::LayoutSpec(lp::Layout::Equirect);
    opt.photometry = photometry;
    opt.rotation = turn;
    opt.handoff = lp::Handoff::Every;
    opt.keepImages = keepImages;
    opt.bracket = lp::MergeOptions{.frames = 3};
    lp::CapturePipeline pipe(std::make_unique<BracketSource>(map), opt);
    pipe.start();
    for (std::size_t n = 0; n < truth.size(); ++n) {
      const auto out = pipe.waitNext();
      ASSERT_TRUE(out.has_value()) << "frame " << n << ": " << pipe.stats().error;
      const float l00 = std::max({truth[n].c[0].r, truth[n].c[0].g, truth[n].c[0].b});
      for (int k = 0; k < lp::kShCount; ++k)
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(out->unsmoothed.c[k][c], truth[n].c[k][c], 1e-5f * l00)
              << "frame " << n << " coefficient " << k << " channel " << c;
      if (keepImages) {
        ASSERT_TRUE(out->background.image) << "frame " << n;
        EXPECT_EQ(out->background.image->rgb.size(), map.rgb.size()) << "frame " << n;
      } else {
        EXPECT_FALSE(out->background.image || out->background.raw) << "frame " << n;
      }
    }
  }
}

// Sources: synthetic is deterministic per frame; sequences by folder and by pattern.
TEST(Sources, SyntheticIsDeterministic) {
  std::vector<float> a, b;
  lp::renderSyntheticSky(64, 32, 1.25, a);
  lp::renderSyntheticSky(64, 32, 1.25, b);
  EXPECT_EQ(a, b);
  lp::renderSyntheticSky(64, 32, 1.5, b);
  EXPECT_NE(a, b);
}

TEST(Sources, ImageSequenceByFolderAndPattern) {
  lpt::TempDir tmp;
  for (int i = 1; i <= 3; ++i) {
    lp::Image img(16, 8);
    std::fill(img.rgb.begin(), img.rgb.end(), float(i));
    lp::saveImage(tmp / ("f_" + std::to_string(i) + ".exr"), img);
  }
  for (const std::string& spec : {tmp.path.string(), tmp / "f_%d.exr"}) {
    auto src = lp::openSource(spec, {10.0});
    lp::Frame f;
    int n = 0;
    while (src->next(f)) {
      ++n;
      EXPECT_FLOAT_EQ(f.rgb[0], float(n));
      EXPECT_NEAR(f.timestamp, (n - 1) / 10.0, 1e-9);
    }
    EXPECT_EQ(n, 3) << spec;
  }
}

// A recording replays to the coefficients of the stream it recorded (8-bit sRGB with the stored
// exposure: quantisation, well under 1% of L00), radiance above code 255 clipped (the sun's core).
TEST(Recording, RoundTripThroughFfv1) {
  lpt::TempDir tmp;
  const std::string file = tmp / "sky.mkv";
  {
    auto src = lp::openSource("synthetic:128x64@30");
    lp::VideoRecorder rec(file, src->fps(), src->describe());
    lp::Frame f;
    for (int i = 0; i < 10 && src->next(f); ++i) rec.write(f);
    rec.finish();
  }
  ASSERT_TRUE(std::filesystem::exists(file));
  ASSERT_TRUE(std::filesystem::exists(file + ".json"));
  auto replay = lp::openSource(file);
  const lp::Projector proj(lp::Layout::Equirect, 128, 64);
  lp::Frame f;
  int n = 0;
  while (replay->next(f)) {
    const lp::Linearizer lin({0.0f, float(f.radianceScale)});
    lp::Image img;
    lin.convert(f, img);
    std::vector<float> truth;
    lp::renderSyntheticSky(128, 64, n / 30.0, truth);
    for (float& v : truth) v = std::min(v, float(f.radianceScale));  // code 255
    EXPECT_NEAR(f.timestamp, n / 30.0, 1e-6);
    const lp::Sh9 a = proj.project(lp::PanoramaView::rgbF32(img.rgb.data(), 128, 64)),
                  b = proj.project(lp::PanoramaView::rgbF32(truth.data(), 128, 64));
    for (int k = 0; k < 9; ++k) EXPECT_NEAR(a.c[k].y, b.c[k].y, 0.01 * b.c[0].y) << lp::kShNames[k];
    ++n;
  }
  EXPECT_EQ(n, 10);
}

}  // namespace

namespace {

// Speed must not cost accuracy: at 3840x1920, one and two threads, the projection is within
// 1e-4 of L00 of a float64 per-pixel reference; a single float running sum (the plain approach
// of google/spherical-harmonics) is not.
TEST(Accuracy, FourKFrameAgainstFloat64) {
  const int w = 3840, h = 1920;
  std::vector<float> sky;
  lp::renderSyntheticSky(w, h, 2.0, sky);
  const auto samples = lp::layoutSamples(lp::Layout::Equirect, w, h);
  std::array<double, 27> ref{};
  std::array<float, 27> naive{};
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const auto y = lp::shBasis(samples[i].dir);
    for (int k = 0; k < 9; ++k)
      for (int c = 0; c < 3; ++c) {
        ref[3 * k + c] += double(sky[3 * i + c]) * y[k] * samples[i].solidAngle;
        naive[3 * k + c] += sky[3 * i + c] * y[k] * samples[i].solidAngle;
      }
  }
  lp::ThreadPool two(2);
  const lp::Projector proj(lp::Layout::Equirect, w, h);
  for (lp::Executor* pool :
       {static_cast<lp::Executor*>(nullptr), static_cast<lp::Executor*>(&two)}) {
    const lp::Sh9 L = proj.project(lp::PanoramaView::rgbF32(sky.data(), w, h), pool);
    for (int k = 0; k < 9; ++k)
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(L.c[k][c], ref[3 * k + c], 1e-4 * ref[c])
            << lp::kShNames[k] << " threads " << (pool ? 2 : 1);
  }
  double naiveErr = 0;
  for (int c = 0; c < 3; ++c) naiveErr = std::max(naiveErr, std::abs(naive[c] - ref[c]) / ref[c]);
  std::cout << "single float running sum: L00 off by " << 100 * naiveErr << "%\n";
  EXPECT_GT(naiveErr, 1e-3) << "the naive sum was expected to lose accuracy at 4K";
}

// 8-bit and half-float inputs give the float result of the same values.
TEST(Accuracy, EightBitAndHalfInputs) {
  const int w = 512, h = 256;
  std::vector<std::uint8_t> bgr(std::size_t(w) * h * 3);
  std::mt19937 rng(3);
  for (auto& v : bgr) v = std::uint8_t(rng());
  const lp::Linearizer lin;
  lp::Frame f;
  f.format = lp::PanoramaFormat::BgrU8, f.width = w, f.height = h, f.bgr8 = bgr;
  lp::Image img;
  lin.convert(f, img);
  for (lp::Layout layout : {lp::Layout::Equirect, lp::Layout::DualFisheye}) {
    const lp::Projector proj(layout, w, h);
    const lp::Sh9 a = proj.project(lp::PanoramaView::rgbF32(img.rgb.data(), w, h, layout)),
                  b = proj.project(
                      lp::PanoramaView::bgrU8(bgr.data(), w, h, lin.table().data(), layout));
    for (int k = 0; k < 9; ++k) EXPECT_NEAR(a.c[k].x, b.c[k].x, 1e-5 * a.c[0].x) << lp::kShNames[k];
  }
  // Half floats: values exactly representable in binary16.
  std::vector<std::uint16_t> half(img.rgb.size());
  std::vector<float> back(img.rgb.size());
  for (std::size_t i = 0; i < half.size(); ++i) {
    const int q = int(rng() % 1024);
    half[i] = std::uint16_t(0x3C00 | q);  // 1 + q/1024
    back[i] = 1.0f + q / 1024.0f;
  }
  const lp::Sh9 a = lp::project(lp::PanoramaView::rgbF32(back.data(), w, h)),
                b = lp::project(lp::PanoramaView::rgbF16(half.data(), w, h));
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(a.c[k].y, b.c[k].y, 1e-6 * a.c[0].y) << lp::kShNames[k];
}

// Projecting a frame reduced by solid-angle-weighted area averaging: the error it introduces,
// measured on real HDRs (the README gives the numbers). Within a block, where the light sits is
// lost, so the error grows with the block size and with how concentrated the light is: under
// 0.1% of L00 at 4x for skies and interiors, about 1.4% for an unoccluded sun.
TEST(Accuracy, ReducedResolutionErrorIsBounded) {
  for (const char* file : {"equirect/pedestrian_overpass_1k.hdr", "equirect/royal_esplanade_1k.hdr",
                           "probes/latlong_full/grace_latlong.exr"}) {
    const lp::Image img = lp::loadImage(lpt::dataPath(file));
    const lp::Sh9 full =
        lp::project(lp::PanoramaView::rgbF32(img.rgb.data(), img.width, img.height));
    const bool sun = std::string(file).find("pedestrian") != std::string::npos;
    double previous = 0;
    for (int f : {2, 4, 8}) {
      const lp::Image small = lp::reduceEquirect(img.rgb.data(), img.width, img.height, f);
      const lp::Sh9 r =
          lp::project(lp::PanoramaView::rgbF32(small.rgb.data(), small.width, small.height));
      double worst = 0;
      for (int k = 0; k < 9; ++k)
        for (int c = 0; c < 3; ++c)
          worst = std::max(worst, double(std::abs(r.c[k][c] - full.c[k][c]) / full.c[0][c]));
      std::cout << file << " reduced " << f << "x: worst coefficient change " << 100 * worst
                << "% of L00\n";
      if (f <= 4) {
        EXPECT_LT(worst, sun ? 0.02 : 1e-3) << file << " factor " << f;
      }
      EXPECT_GT(worst, previous) << "error must grow with the block size";
      previous = worst;
      EXPECT_NEAR(r.c[0].x, full.c[0].x, 1e-5 * full.c[0].x) << "power is kept exactly";
    }
  }
}

}  // namespace
