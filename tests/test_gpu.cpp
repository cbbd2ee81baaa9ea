// The GPU path on EGL (Mesa's llvmpipe here, a GPU where there is one): the EGL context renders
// what OSMesa renders; the compute projection gives the CPU projector's coefficients for every
// layout (a calibrated lens and a ball traced through one too) and pixel type; frames through the
// pixel-buffer objects equal frames uploaded directly; coefficients come back one frame late
// without waiting; the timer says when there is no GPU timer. One process, one context type: glad's
// pointers belong to the context that loaded them, so the OSMesa comparison runs the program twice.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "layout_dirs.h"
#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/lens.h"
#include "liveprobe/frame/srgb.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/gl/gpu_merge.h"
#include "liveprobe/gl/gpu_projector.h"
#include "liveprobe/gl/gpu_timer.h"
#include "liveprobe/gl/renderer.h"
#include "liveprobe/hdr/merge.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/projector.h"
#include "test_util.h"
#include "turned_map.h"

namespace {

lp::gl::GlContext& eglContext() {
  static auto ctx = lp::gl::createGlContext({lp::gl::Backend::Egl, 64, 64, "gpu tests", false});
  return *ctx;
}

/// Half-precision bits of a float (round to nearest even; values here are normal or zero).
std::uint16_t toHalf(float f) {
  std::uint32_t x;
  std::memcpy(&x, &f, 4);
  const std::uint32_t sign = (x >> 16) & 0x8000u;
  const int exp = int((x >> 23) & 0xff) - 127 + 15;
  std::uint32_t mant = x & 0x7fffffu;
  if (exp <= 0) return std::uint16_t(sign);
  std::uint32_t h = sign | (std::uint32_t(exp) << 10) | (mant >> 13);
  const std::uint32_t rest = mant & 0x1fffu;
  if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) ++h;
  return std::uint16_t(h);
}

/// A frame of every pixel type holding the same scene: sky, ground and a sun 1e3 times brighter,
/// with noise so that no two pixels are alike.
struct Frames {
  int w, h;
  std::vector<float> f32;
  std::vector<std::uint16_t> f16;
  std::vector<std::uint8_t> u8;
  std::array<float, 256> decode;
};
Frames makeFrames(int w, int h) {
  Frames f{w, h, {}, {}, {}, {}};
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> noise(0.8f, 1.2f);
  for (int c = 0; c < 256; ++c) f.decode[std::size_t(c)] = std::pow(c / 255.0f, 2.2f) * 3.0f;
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j)
      for (int c = 0; c < 3; ++c) {
        const bool sun = std::abs(i - h / 4) <= h / 16 && std::abs(j - w / 3) <= w / 32;
        const float v = (sun ? 1000.0f : (i < h / 2 ? 0.6f + 0.2f * c : 0.2f)) * noise(rng);
        f.f32.push_back(v);
        f.f16.push_back(toHalf(v));
        f.u8.push_back(std::uint8_t(std::min(255.0f, 255.0f * std::pow(v / 3.0f, 1 / 2.2f))));
      }
  return f;
}

double ofL00(const lp::Sh9& gpu, const lp::Sh9& cpu) {
  double worst = 0;
  for (int k = 0; k < lp::kShCount; ++k)
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, double(std::abs(gpu.c[k][c] - cpu.c[k][c])));
  return worst / double(std::max({cpu.c[0].x, cpu.c[0].y, cpu.c[0].z}));
}

struct LayoutCase {
  const char* name;
  lp::LayoutSpec spec;
  int w, h;
};
std::vector<LayoutCase> layoutCases() {
  lp::LayoutSpec ball(lp::Layout::MirrorBall);
  ball.circle = {70, 60, 50};
  lp::LayoutSpec fisheye(lp::Layout::DualFisheye);
  fisheye.fisheyeFovDeg = 200;
  // A calibrated fisheye (the project's 640x480 Kannala-Brandt lens, at half its size) with the
  // unseen ground filled, and a chrome ball traced through it.
  const lp::LensCalibration camera =
      lp::readLensCalibration(std::string(LIVEPROBE_SOURCE_DIR) + "/recordings/fisheye/lens.yaml");
  lp::LayoutSpec lens(lp::Layout::Lens);
  lens.lens = lp::makeLensModel(camera);
  lp::LayoutSpec traced(lp::Layout::MirrorBall);
  traced.circle = {330, 230, 120};
  traced.lens = lp::makeBallModel(camera, traced.circle);
  return {{"equirect", lp::Layout::Equirect, 128, 64},
          {"equirect odd", lp::Layout::Equirect, 301, 149},
          {"angular", lp::Layout::Angular, 96, 96},
          {"mirrorball", ball, 150, 120},
          {"cube", lp::Layout::Cube, 128, 96},
          {"fisheye", fisheye, 160, 80},
          {"lens", lens, 320, 240},
          {"traced ball", traced, 640, 480}};
}

TEST(GpuProjection, MatchesTheCpuForEveryLayoutAndPixelType) {
  eglContext();
  ASSERT_TRUE(lp::gl::hasCompute()) << "Mesa's EGL offers GL 4.5 with compute";
  for (const LayoutCase& lc : layoutCases()) {
    const Frames f = makeFrames(lc.w, lc.h);
    const lp::Projector cpu(lc.spec, lc.w, lc.h);
    lp::gl::GpuProjector gpu(lc.spec, lc.w, lc.h);
    lp::gl::FrameTexture tex;
    struct Type {
      const char* name;
      lp::PanoramaView view;
    };
    const Type types[] = {
        {"f32", {f.f32.data(), lp::PanoramaFormat::RgbF32, lc.w, lc.h, 0, lc.spec, nullptr}},
        {"f16", {f.f16.data(), lp::PanoramaFormat::RgbF16, lc.w, lc.h, 0, lc.spec, nullptr}},
        {"u8 rgb",
         {f.u8.data(), lp::PanoramaFormat::RgbU8, lc.w, lc.h, 0, lc.spec, f.decode.data()}},
        {"u8 bgr",
         {f.u8.data(), lp::PanoramaFormat::BgrU8, lc.w, lc.h, 0, lc.spec, f.decode.data()}},
    };
    for (const Type& t : types) {
      tex.upload(t.view);
      const lp::Sh9 want = cpu.project(t.view);
      const lp::Sh9 got =
          gpu.project(tex, t.view.decode, t.view.format == lp::PanoramaFormat::BgrU8);
      EXPECT_LT(ofL00(got, want), 1e-5) << lc.name << " " << t.name;
      // And not by accident: the sun is in there, and the channels are where they belong.
      EXPECT_GT(std::abs(want.c[1].x), 1e-3f * want.c[0].x) << lc.name;
    }
  }
}

/// The test frames as the frame path takes them: 8-bit (BGR) or float.
std::shared_ptr<lp::Frame> pathFrame(const Frames& f, bool u8) {
  auto frame = std::make_shared<lp::Frame>();
  frame->width = f.w, frame->height = f.h;
  frame->format = u8 ? lp::PanoramaFormat::BgrU8 : lp::PanoramaFormat::RgbF32;
  if (u8)
    frame->bgr8 = f.u8;
  else
    frame->rgb = f.f32;
  return frame;
}

// The frame path with the GPU's projection (what --projection gpu gives every command): every
// layout, 8-bit and float frames, and a reduction, give the CPU path's coefficients; and a light
// search from the GPU's row peaks finds the CPU path's lights.
TEST(GpuProjection, TheFramePathOnTheGpuEqualsTheCpuPath) {
  eglContext();
  for (const LayoutCase& lc : layoutCases())
    for (const bool u8 : {true, false})
      for (const int reduce : {1, 2}) {
        if (reduce > 1 && (lc.spec.layout != lp::Layout::Equirect || lc.w % 2 || lc.h % 2))
          continue;
        const Frames f = makeFrames(lc.w, lc.h);
        const auto frame = pathFrame(f, u8);
        const lp::FrameProcessorOptions o{
            lc.spec, lp::Photometry{}, std::nullopt, reduce, {.maxLights = 0}};
        lp::FrameProcessor cpu(o), gpu(o);
        lp::gl::GpuFrameProjection onGpu;
        const lp::FrameResult want = cpu.run(frame);
        const lp::FrameResult got = gpu.run(frame, {.projectWith = std::ref(onGpu)});
        const std::string what =
            std::string(lc.name) + (u8 ? " u8" : " f32") + (reduce > 1 ? " reduced" : "");
        EXPECT_EQ(want.projectedOn, lp::ProjectedOn::Cpu) << what;
        EXPECT_EQ(got.projectedOn, lp::ProjectedOn::Gpu) << what;
        EXPECT_LT(ofL00(got.lighting.whole, want.lighting.whole), 1e-5) << what;
        EXPECT_GT(std::abs(want.lighting.whole.c[1].x), 1e-3f * want.lighting.whole.c[0].x) << what;
      }
  // The sun: the row peaks equal the CPU's, and so the lights (an equirect frame, whose peaks the
  // CPU takes inside its projection, and a mirror ball, whose peaks it reads apart). A sun of 4
  // degrees' radius over a sky; 8-bit: clipped at 255.
  lp::LayoutSpec ball(lp::Layout::MirrorBall);
  ball.circle = {100, 100, 95};
  const LayoutCase suns[] = {{"equirect", lp::Layout::Equirect, 256, 128},
                             {"mirrorball", ball, 200, 200}};
  const lpt::DirAt dirs[] = {lpt::equirectDirs(256, 128), lpt::mirrorBallDirs(100, 100, 95)};
  for (int c = 0; c < 2; ++c)
    for (const bool u8 : {true, false}) {
      const LayoutCase& lc = suns[c];
      const glm::dvec3 sun =
          glm::normalize(*dirs[c](c == 0 ? 256 / 3.0 : 120.0, c == 0 ? 32.0 : 80.0));
      Frames f{lc.w, lc.h, {}, {}, {}, {}};
      for (int i = 0; i < lc.h; ++i)
        for (int j = 0; j < lc.w; ++j) {
          const auto d = dirs[c](j + 0.5, i + 0.5);
          const bool inSun = d && glm::dot(glm::normalize(*d), sun) > std::cos(glm::radians(4.0));
          const double sky = d ? 0.5 + 0.3 * glm::normalize(*d).z : 0.0;
          for (int k = 0; k < 3; ++k) {
            f.f32.push_back(inSun ? 3000.0f : float(sky * (0.8 + 0.1 * k)));
            f.u8.push_back(inSun ? 255 : std::uint8_t(d ? 20 + 20 * sky + 5 * k : 0));
          }
        }
      const auto frame = pathFrame(f, u8);
      const std::string what = std::string(lc.name) + (u8 ? " u8" : " f32");
      const lp::FrameProcessorOptions o{
          lc.spec, lp::Photometry{}, std::nullopt, 1, {.maxLights = 2}};
      lp::FrameProcessor cpu(o), gpu(o);
      lp::gl::GpuFrameProjection onGpu;
      std::vector<float> gpuPeaks;
      const lp::FrameLighting want = cpu.run(frame).lighting;
      const lp::FrameLighting got = gpu.run(frame, {.projectWith =
                                                        [&](const lp::ProjectionJob& job) {
                                                          const lp::Sh9 whole = onGpu(job);
                                                          if (job.rowPeaks)
                                                            gpuPeaks = *job.rowPeaks;
                                                          return whole;
                                                        }})
                                        .lighting;
      std::vector<float> cpuPeaks;
      const lp::FrameProcessor& p = cpu;
      (void)p.projector()->project(
          u8 ? lp::PanoramaView::bgrU8(frame->bgr8.data(), lc.w, lc.h,
                                       cpu.linearizer().table().data(), lc.spec)
             : lp::PanoramaView::rgbF32(frame->rgb.data(), lc.w, lc.h, lc.spec),
          nullptr, &cpuPeaks);
      EXPECT_EQ(gpuPeaks, cpuPeaks) << what;
      ASSERT_FALSE(want.lights.empty()) << what;
      ASSERT_EQ(got.lights.size(), want.lights.size()) << what;
      for (std::size_t k = 0; k < want.lights.size(); ++k) {
        const double deg = glm::degrees(std::acos(
            std::clamp(double(glm::dot(got.lights[k].dir, want.lights[k].dir)), -1.0, 1.0)));
        EXPECT_LT(deg, 0.05) << what;
        EXPECT_NEAR(got.lights[k].share, want.lights[k].share, 0.01 * want.lights[k].share) << what;
      }
      EXPECT_LT(ofL00(got.radiance, want.radiance), 1e-5) << what;
    }
}

// Several rows per invocation, and row counts that leave a remainder, give the same sums.
TEST(GpuProjection, AnyRowsPerGroupGiveTheSameCoefficients) {
  eglContext();
  const Frames f = makeFrames(200, 100);
  const auto view = lp::PanoramaView::rgbF32(f.f32.data(), 200, 100);
  const lp::Sh9 want = lp::Projector(lp::Layout::Equirect, 200, 100).project(view);
  lp::gl::FrameTexture tex;
  tex.upload(view);
  for (int rows : {1, 3, 7, 64, 100}) {
    lp::gl::GpuProjector gpu(lp::Layout::Equirect, 200, 100, rows);
    EXPECT_LT(ofL00(gpu.project(tex), want), 1e-5) << rows << " rows";
  }
}

TEST(GpuProjection, FramesThroughThePixelBuffersEqualDirectUploads) {
  eglContext();
  const int w = 130, h = 65;  // rows of 390 bytes: not a multiple of 4
  const Frames f = makeFrames(w, h);
  for (const auto format : {lp::PanoramaFormat::RgbF32, lp::PanoramaFormat::RgbU8}) {
    const bool u8 = format == lp::PanoramaFormat::RgbU8;
    const void* pixels = u8 ? static_cast<const void*>(f.u8.data()) : f.f32.data();
    lp::gl::FrameTexture tex;
    // Three frames through the two buffers in turn; the last one is what the texture holds.
    std::vector<std::uint8_t> zeros(std::size_t(w) * h * (u8 ? 3 : 12), 0);
    for (const void* frame : {static_cast<const void*>(zeros.data()), pixels, pixels}) {
      const lp::PanoramaView v{frame, format, w, h, 0, {}, f.decode.data()};
      tex.upload(v);
    }
    GLuint direct = 0;
    glGenTextures(1, &direct);
    glBindTexture(GL_TEXTURE_2D, direct);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, u8 ? GL_RGB8 : GL_RGB32F, w, h, 0, GL_RGB,
                 u8 ? GL_UNSIGNED_BYTE : GL_FLOAT, pixels);
    const std::size_t bytes = std::size_t(w) * h * (u8 ? 3 : 12);
    std::vector<std::uint8_t> a(bytes), b(bytes);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RGB, u8 ? GL_UNSIGNED_BYTE : GL_FLOAT, b.data());
    glBindTexture(GL_TEXTURE_2D, tex.texture());
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RGB, u8 ? GL_UNSIGNED_BYTE : GL_FLOAT, a.data());
    glDeleteTextures(1, &direct);
    EXPECT_EQ(a, b) << (u8 ? "u8" : "f32");
    EXPECT_EQ(std::memcmp(a.data(), pixels, bytes), 0) << (u8 ? "u8" : "f32");
    EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  }
}

// dispatch() returns at once; read() hands the frames back in order, the newest one frame late.
TEST(GpuProjection, CoefficientsComeBackInOrderOneFrameLate) {
  eglContext();
  const Frames f = makeFrames(64, 32);
  std::vector<float> dim(f.f32.size());
  for (std::size_t i = 0; i < dim.size(); ++i) dim[i] = f.f32[i] * 0.5f;
  lp::gl::FrameTexture a, b;
  a.upload(lp::PanoramaView::rgbF32(f.f32.data(), 64, 32));
  b.upload(lp::PanoramaView::rgbF32(dim.data(), 64, 32));
  lp::gl::GpuProjector gpu(lp::Layout::Equirect, 64, 32);
  EXPECT_FALSE(gpu.read(false).has_value()) << "nothing dispatched";
  gpu.dispatch(a);
  gpu.dispatch(b);
  EXPECT_EQ(gpu.pending(), 2);
  const lp::Sh9 first = *gpu.read(true), second = *gpu.read(true);
  EXPECT_EQ(gpu.pending(), 0);
  EXPECT_NEAR(second.c[0].x, 0.5f * first.c[0].x, 1e-5f * first.c[0].x);
  // A third frame while two are in flight takes the oldest first: none is lost.
  gpu.dispatch(a), gpu.dispatch(b), gpu.dispatch(a);
  EXPECT_EQ(gpu.pending(), 2);
  EXPECT_NEAR(gpu.read(true)->c[0].x, second.c[0].x, 1e-6f * first.c[0].x);
  EXPECT_NEAR(gpu.read(true)->c[0].x, first.c[0].x, 1e-6f * first.c[0].x);
}

TEST(GpuProjection, RefusesAFrameOfAnotherSizeOrWithoutItsTable) {
  eglContext();
  const Frames f = makeFrames(64, 32);
  lp::gl::FrameTexture tex;
  tex.upload(lp::PanoramaView{f.u8.data(), lp::PanoramaFormat::RgbU8, 64, 32, 0, {}, nullptr});
  lp::gl::GpuProjector gpu(lp::Layout::Equirect, 64, 32);
  EXPECT_THROW(gpu.dispatch(tex), lp::Error);
  lp::gl::GpuProjector other(lp::Layout::Equirect, 32, 16);
  EXPECT_THROW(other.dispatch(tex, f.decode.data()), lp::Error);
  EXPECT_EQ(gpu.pending() + other.pending(), 0);
}

// On llvmpipe there is no GPU timer: the timer says so (no 0 ms), and asking never blocks.
TEST(GpuTimer, SaysThereIsNoGpuTimerOnASoftwareRasterizer) {
  eglContext();
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  lp::gl::GpuTimer timer;
  const Frames f = makeFrames(64, 32);
  lp::gl::FrameTexture tex;
  lp::gl::GpuProjector gpu(lp::Layout::Equirect, 64, 32);
  for (int frame = 0; frame < 12; ++frame) {
    timer.beginFrame();
    timer.begin(lp::gl::GpuTimer::Upload);
    tex.upload(lp::PanoramaView::rgbF32(f.f32.data(), 64, 32));
    timer.end();
    timer.begin(lp::gl::GpuTimer::Project);
    gpu.dispatch(tex);
    timer.end();
    gpu.read(true);
  }
  if (lp::gl::isSoftwareRenderer(renderer)) {
    EXPECT_FALSE(timer.hasTimer()) << renderer;
    EXPECT_FALSE(timer.ms(lp::gl::GpuTimer::Project).has_value());
  } else {
    ASSERT_TRUE(timer.hasTimer()) << renderer;
    EXPECT_GT(*timer.ms(lp::gl::GpuTimer::Project), 0.0);
  }
  EXPECT_THROW(timer.end(), std::logic_error) << "end without begin";
  EXPECT_TRUE(lp::gl::isSoftwareRenderer("llvmpipe (LLVM 15.0.6, 256 bits)"));
  EXPECT_FALSE(lp::gl::isSoftwareRenderer("NVIDIA H100 80GB HBM3/PCIe/SSE2"));
}

// The same scene through EGL and through OSMesa (both llvmpipe here): the same image, and each
// run names the GL it drew with.
TEST(Egl, RendersWhatOsMesaRenders) {
  const std::string dir = std::string(LIVEPROBE_TEST_OUTPUT) + "/gpu";
  std::filesystem::create_directories(dir);
  cv::Mat images[2];
  const char* backends[] = {"egl", "osmesa"};
  const char* says[] = {"EGL device", "OSMesa"};
  for (int b = 0; b < 2; ++b) {
    const std::string out = dir + "/bunny_" + backends[b] + ".png";
    const auto r =
        lpt::runLiveprobe("render --env " + lpt::dataPath("equirect/pedestrian_overpass_1k.hdr") +
                          " --model " + lpt::dataPath("models/stanford-bunny.obj") +
                          " --sun --size 320x240 --gl " + backends[b] + " --out " + out);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find(says[b]), std::string::npos) << r.output;
    images[b] = cv::imread(out);
    ASSERT_FALSE(images[b].empty()) << out;
  }
  cv::Mat diff;
  cv::absdiff(images[0], images[1], diff);
  double maxDiff = 0;
  cv::minMaxLoc(diff.reshape(1), nullptr, &maxDiff);
  EXPECT_LE(maxDiff, 2.0) << "EGL and OSMesa drew different images";
  EXPECT_LT(cv::mean(diff)[0], 0.05);
}

// EGL in hostile surroundings: no EGL vendor library, a driver that does not load, a GL too old
// for the renderer or for the compute projection, a size beyond the renderer's: one line that
// names what failed, exit 1, and no output left behind. (Mesa's own warnings stay quiet.)
TEST(Egl, HostileSurroundingsAreOneLine) {
  const std::string out = std::string(LIVEPROBE_TEST_OUTPUT) + "/gpu/hostile.png";
  const std::string render = " render --coeff L00=1 --size 64x64 --gl egl --out " + out;
  struct Case {
    std::string env, args, says;
  };
  const Case cases[] = {
      {"__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json", render, "cannot open EGL"},
      {"GALLIUM_DRIVER=nonexistent LIBGL_ALWAYS_SOFTWARE=1", render, "EGL"},
      {"MESA_GL_VERSION_OVERRIDE=3.1", render, "GL 3.3 core"},
      {"MESA_GL_VERSION_OVERRIDE=3.3 MESA_GLSL_VERSION_OVERRIDE=330",
       " bench --frames 2 --repeat 1 --size 160x90 --gl egl --projection gpu",
       "no compute shaders (GL 4.3)"},
      {"", " render --coeff L00=1 --size 30000x30000 --gl egl --out " + out, "at most"},
  };
  for (const Case& c : cases) {
    std::filesystem::create_directories(std::filesystem::path(out).parent_path());
    std::filesystem::remove(out);
    const auto r = lpt::runCommand("env " + c.env + " " + LIVEPROBE_BIN + c.args);
    EXPECT_EQ(r.exitCode, 1) << c.env << c.args << "\n" << r.output;
    EXPECT_EQ(lpt::lineCount(r.output), 1) << c.env << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << c.env << c.args << "\n" << r.output;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.env << c.args;
  }
}

TEST(Egl, AnEglDeviceThatDoesNotExistIsOneLine) {
  lpt::expectOneLineError("render --coeff L00=1 --size 64x64 --gl egl --gpu 63 --out " +
                              std::string(LIVEPROBE_TEST_OUTPUT) + "/gpu/none.png",
                          "EGL", "no device 63");
  EXPECT_FALSE(std::filesystem::exists(std::string(LIVEPROBE_TEST_OUTPUT) + "/gpu/none.png"));
}

}  // namespace

namespace {

nlohmann::json benchJson(const std::string& args, std::string& output) {
  const std::string json = std::string(LIVEPROBE_TEST_OUTPUT) + "/gpu/bench.json";
  std::filesystem::create_directories(std::filesystem::path(json).parent_path());
  const auto r =
      lpt::runLiveprobe("bench --frames 3 --repeat 1 --size 160x90 --json " + json + " " + args);
  output = r.output;
  EXPECT_EQ(r.exitCode, 0) << r.output;
  std::ifstream in(json);
  return nlohmann::json::parse(in);
}

// bench on EGL: the projection on the GPU gives the CPU's coefficients for the same frames, auto
// keeps llvmpipe's projection on the CPU, and a software rasterizer's GPU time is "no GPU timer".
TEST(BenchOnEgl, GpuAndCpuProjectionsGiveTheSameCoefficients) {
  std::string gpuOut, cpuOut, autoOut;
  const auto gpu = benchJson("--gl egl --projection gpu", gpuOut);
  const auto cpu = benchJson("--gl egl --projection cpu", cpuOut);
  const auto autoRun = benchJson("--gl egl", autoOut);
  EXPECT_EQ(gpu["projection"], "gpu");
  EXPECT_EQ(cpu["projection"], "cpu");
  EXPECT_NE(gpu["gl"].get<std::string>().find("EGL"), std::string::npos) << gpu["gl"];
  EXPECT_NE(gpuOut.find("; projection on the GPU"), std::string::npos) << gpuOut;
  EXPECT_NE(gpuOut.find("drawn with EGL"), std::string::npos) << gpuOut;
  const auto& a = gpu["last_coefficients"];
  const auto& b = cpu["last_coefficients"];
  ASSERT_EQ(a.size(), 9u);
  const double l00 = b[0][1].get<double>();
  ASSERT_GT(l00, 0.0);
  for (int k = 0; k < 9; ++k)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(a[k][c].get<double>(), b[k][c].get<double>(), 1e-5 * l00) << k << "," << c;
  if (lp::gl::isSoftwareRenderer(gpu["gl"].get<std::string>())) {
    EXPECT_EQ(autoRun["projection"], "cpu") << "llvmpipe projects slower than the CPU";
    EXPECT_EQ(gpu["gpu"]["timer"], false);
    EXPECT_NE(gpuOut.find("no GPU timer"), std::string::npos) << gpuOut;
    EXPECT_EQ(gpuOut.find("gpu_render"), std::string::npos) << "no 0 ms where there is no timer";
  }
}

/// A headless replay's records (--coeffs-out), one JSON object a frame.
std::vector<nlohmann::json> replayRecords(const std::string& args, std::string& output) {
  const std::string file = std::string(LIVEPROBE_TEST_OUTPUT) + "/gpu/replay.jsonl";
  std::filesystem::create_directories(std::filesystem::path(file).parent_path());
  const auto r = lpt::runLiveprobe("replay --headless --gl egl --frames 4 --size 64x36 --quiet " +
                                   args + " --coeffs-out " + file);
  output = r.output;
  EXPECT_EQ(r.exitCode, 0) << args << "\n" << r.output;
  std::vector<nlohmann::json> out;
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) out.push_back(nlohmann::json::parse(line));
  return out;
}

// A stream projected on the GPU (the capture thread's own EGL context): the CPU's coefficients
// and lights frame by frame, with a reduction too; the summary says where frames were projected,
// and auto keeps llvmpipe's projection on the CPU; llvmpipe's GPU time is "no GPU timer".
TEST(ReplayOnEgl, ProjectsOnTheGpuWhereAsked) {
  for (const std::string extra : {"--sun", "--reduce 2"}) {
    std::string gpuOut, cpuOut, autoOut;
    const auto gpu = replayRecords("--projection gpu " + extra, gpuOut);
    const auto cpu = replayRecords("--projection cpu " + extra, cpuOut);
    const auto autoRun = replayRecords(extra, autoOut);
    EXPECT_NE(gpuOut.find("projected on the GPU, EGL"), std::string::npos) << gpuOut;
    EXPECT_NE(gpuOut.find(": 4 of 4 frames"), std::string::npos) << gpuOut;
    EXPECT_NE(cpuOut.find("projected on the CPU"), std::string::npos) << cpuOut;
    if (lp::gl::isSoftwareRenderer(gpuOut)) {
      EXPECT_NE(autoOut.find("projected on the CPU"), std::string::npos) << autoOut;
      // No GPU timer on a software rasterizer: said, and no GPU time in any record (never 0 ms).
      EXPECT_NE(gpuOut.find("GPU time: no GPU timer (EGL"), std::string::npos) << gpuOut;
      for (const auto& r : gpu)
        for (const char* key : {"gpu_upload", "gpu_project", "gpu_merge", "gpu_render"})
          EXPECT_FALSE(r["timings_ms"].contains(key)) << key << " " << r["timings_ms"];
    }
    ASSERT_EQ(gpu.size(), 4u) << extra;
    ASSERT_EQ(cpu.size(), 4u) << extra;
    for (std::size_t i = 0; i < gpu.size(); ++i) {
      const auto& a = gpu[i]["coefficients"];
      const auto& b = cpu[i]["coefficients"];
      const double l00 = b["L00"][1].get<double>();
      ASSERT_GT(l00, 0.0);
      for (const auto& [name, value] : b.items())
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(a[name][c].get<double>(), value[c].get<double>(), 1e-5 * l00)
              << extra << " frame " << i << " " << name;
      if (extra == "--sun") {
        ASSERT_EQ(gpu[i]["lights"].size(), cpu[i]["lights"].size()) << i;
        ASSERT_FALSE(cpu[i]["lights"].empty()) << "the recording's sun";
        const auto& la = gpu[i]["lights"][0];
        const auto& lb = cpu[i]["lights"][0];
        double dot = 0;
        for (int c = 0; c < 3; ++c)
          dot += la["direction"][c].get<double>() * lb["direction"][c].get<double>();
        EXPECT_LT(glm::degrees(std::acos(std::min(1.0, dot))), 0.05) << i;
        EXPECT_NEAR(la["share"].get<double>(), lb["share"].get<double>(),
                    0.01 * lb["share"].get<double>())
            << i;
      }
    }
  }
}

// --projection gpu where the context cannot: one line, exit 1, for every command that projects.
TEST(ReplayOnEgl, GpuProjectionWithoutAGpuContextIsOneLine) {
  const std::string env = std::string(LIVEPROBE_SOURCE_DIR) + "/recordings/sky-hdr/0000.exr";
  const std::string noCompute = "env MESA_GL_VERSION_OVERRIDE=3.3 MESA_GLSL_VERSION_OVERRIDE=330 ";
  struct Case {
    std::string command, says;
  };
  const Case cases[] = {
      {noCompute + LIVEPROBE_BIN + " replay --headless --gl egl --frames 2 --projection gpu",
       "no compute shaders (GL 4.3)"},
      {noCompute + LIVEPROBE_BIN + " render --gl egl --projection gpu --size 32x32 --env " + env +
           " --out " + LIVEPROBE_TEST_OUTPUT + "/gpu/refused.png",
       "no compute shaders (GL 4.3)"},
      {std::string(LIVEPROBE_BIN) + " replay --headless --gl osmesa --frames 2 --projection gpu",
       "headless EGL context"},
  };
  for (const Case& c : cases) {
    const auto r = lpt::runCommand(c.command);
    EXPECT_EQ(r.exitCode, 1) << c.command << "\n" << r.output;
    EXPECT_EQ(lpt::lineCount(r.output), 1) << c.command << "\n" << r.output;
    EXPECT_NE(r.output.find("--projection gpu"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << r.output;
  }
  EXPECT_FALSE(std::filesystem::exists(std::string(LIVEPROBE_TEST_OUTPUT) + "/gpu/refused.png"));
}

// render on the GPU: the map projected there, said so.
TEST(ReplayOnEgl, RenderProjectsItsMapOnTheGpuWhereAsked) {
  const std::string env = std::string(LIVEPROBE_SOURCE_DIR) + "/recordings/sky-hdr/0000.exr";
  const std::string out = std::string(LIVEPROBE_TEST_OUTPUT) + "/gpu/render.png";
  const auto r = lpt::runLiveprobe("render --gl egl --projection gpu --size 64x64 --env " + env +
                                   " --out " + out);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("--env projected on the GPU"), std::string::npos) << r.output;
}

// A bracket as an 8-bit sRGB camera reads it: a sky from 0.02 at the horizon to 0.2 at the
// zenith over a dark ground, and a sun 2000 times brighter in a 3-pixel disc that moves 7 pixels
// a frame, the scene 10% brighter every other frame; taken at 1, 1/64 and 1/4096 s in turn.
std::vector<lp::Frame> movingBracket(int w, int h, int count) {
  std::vector<lp::Frame> frames;
  for (int i = 0; i < count; ++i) {
    const double t = std::array{1.0, 1.0 / 64, 1.0 / 4096}[std::size_t(i % 3)];
    const int sunX = 30 + 7 * i;
    lp::Frame f;
    f.format = lp::PanoramaFormat::BgrU8;
    f.width = w, f.height = h, f.sequence = std::uint64_t(i);
    f.radianceScale = 1.0 / t;
    f.bgr8.resize(std::size_t(w) * h * 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        float v = y < h / 2 ? 0.02f + 0.18f * float(h / 2 - y) / float(h / 2) : 0.01f;
        if ((x - sunX) * (x - sunX) + (y - 12) * (y - 12) <= 2) v = 400.0f;
        v *= 1.0f + 0.1f * float(i % 2);
        const float rgb[3] = {v, 0.9f * v, 0.8f * v};
        for (int c = 0; c < 3; ++c) {
          const float e = std::clamp(float(rgb[c] * t), 0.0f, 1.0f);
          f.bgr8[(std::size_t(y) * w + x) * 3 + 2 - std::size_t(c)] =
              std::uint8_t(std::lround(255.0f * lp::linearToSrgb(e)));
        }
      }
    frames.push_back(std::move(f));
  }
  return frames;
}

// The bracket merge on the GPU (gl::GpuMerge as the merger's pixel loop) against the CPU's row
// kernel, pixel by pixel, on a bracket whose sun moves (older readings contradicted, light lost,
// a clipped sun) in windows of 3 and 5 frames, in workgroups of 32, 128 and 256 invocations and a
// row in one workgroup or three, a width that fills no workgroup: each merged
// value within 1e-5 of the CPU's, the coefficients projected in the same pass within 1e-5 of
// L00, and every confidence term within 1e-5; each frame uploaded once, however many merges
// read it, and the last merges' luminance never again.
TEST(GpuMerge, EveryPixelIsTheCpusMerge) {
  eglContext().makeCurrent();
  if (!lp::gl::hasCompute()) GTEST_FAIL() << "Mesa's EGL has compute shaders";
  constexpr int w = 125, h = 64;
  const auto frames = movingBracket(w, h, 9);
  const lp::Projector projector(lp::Layout::Equirect, w, h);
  std::vector<lp::FrameConfidence> said;
  // A row in one workgroup, and in three (spans of 42, 42 and 41 pixels); workgroups of 128
  // invocations, and of 32 and 256.
  for (const auto& [parts, group] : {std::pair{1, 128}, {3, 128}, {1, 32}, {1, 256}})
    for (const int window : {3, 5}) {
      lp::gl::GpuMerge gpu({.rowParts = parts, .groupSize = group});
      lp::BracketMerger cpu(lp::MergeOptions{.frames = window}),
          onGpu(lp::MergeOptions{.frames = window});
      // The luminance kept on the GPU, read back only where the merger asks.
      std::size_t fetched = 0;
      onGpu.setFrameKernel(
          [&](const lp::merge::FrameInput& in, std::vector<lp::merge::RowSums>& rows) {
            EXPECT_FALSE(in.luminanceBack);
            gpu(in, rows);
          },
          false,
          [&](std::uint64_t key, float* into) { return ++fetched, gpu.readLuminance(key, into); });
      const std::size_t uploadedBefore = gpu.framesUploaded(),
                        luminanceBefore = gpu.luminanceUploaded();
      for (const lp::Frame& f : frames) {
        lp::Frame a, b;
        lp::MergeProjection pa{.integrals = projector.equirectIntegrals()}, pb = pa;
        const lp::FrameConfidence ca = cpu.add(f, a, nullptr, pa),
                                  cb = onGpu.add(f, b, nullptr, pb);
        const std::string what = std::to_string(parts) + " parts of " + std::to_string(group) +
                                 ", window " + std::to_string(window) + ", frame " +
                                 std::to_string(f.sequence);
        ASSERT_EQ(a.rgb.size(), b.rgb.size());
        for (std::size_t i = 0; i < a.rgb.size(); ++i)
          ASSERT_NEAR(b.rgb[i], a.rgb[i], 1e-5f * a.rgb[i] + 1e-9f) << what << " value " << i;
        for (int k = 0; k < lp::kShCount; ++k)
          for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(pb.coefficients.c[k][c], pa.coefficients.c[k][c],
                        1e-5 * pa.coefficients.c[0][1])
                << what << " coefficient " << k;
        // Each row's largest channel value, where a light search starts.
        ASSERT_EQ(pb.rowPeaks.size(), std::size_t(h)) << what;
        for (int y = 0; y < h; ++y)
          EXPECT_NEAR(pb.rowPeaks[std::size_t(y)], pa.rowPeaks[std::size_t(y)],
                      1e-5f * pa.rowPeaks[std::size_t(y)])
              << what << " row " << y;
        EXPECT_NEAR(cb.value(), ca.value(), 1e-5) << what;
        EXPECT_NEAR(cb.agreement, ca.agreement, 1e-5) << what;
        EXPECT_NEAR(cb.clippedShare, ca.clippedShare, 1e-5) << what;
        EXPECT_EQ(cb.darkShare, ca.darkShare) << what;
        EXPECT_EQ(cb.brightestMeasured, ca.brightestMeasured) << what;
        EXPECT_EQ(cb.complete, ca.complete) << what;
        said.push_back(ca);
      }
      // The camera did not turn: each frame went up once, the older ones kept on the GPU, and the
      // last merges' luminance stayed there (the first merge's two, zeros, uploaded).
      EXPECT_EQ(gpu.framesUploaded() - uploadedBefore, frames.size()) << "window " << window;
      EXPECT_EQ(gpu.luminanceUploaded() - luminanceBefore, 2u) << "window " << window;
      EXPECT_EQ(fetched, 0u) << "window " << window << ": the camera did not turn";
    }
  // The run exercised what it is meant to: light found contradicted, and a clipped sun.
  EXPECT_TRUE(std::any_of(said.begin(), said.end(), [](auto& c) { return c.agreement < 0.99; }));
  EXPECT_TRUE(std::any_of(said.begin(), said.end(), [](auto& c) { return !c.brightestMeasured; }));
  // The bound without the judgement (a measuring aid) is not the CPU's merge here: the moving
  // sun's older readings are kept.
  lp::gl::GpuMerge bound({.judge = false});
  lp::BracketMerger cpu(lp::MergeOptions{.frames = 3}), onBound(lp::MergeOptions{.frames = 3});
  onBound.setFrameKernel([&](const lp::merge::FrameInput& in,
                             std::vector<lp::merge::RowSums>& rows) { bound(in, rows); });
  float worst = 0;
  for (const lp::Frame& f : frames) {
    lp::Frame a, b;
    cpu.add(f, a, nullptr), onBound.add(f, b, nullptr);
    for (std::size_t i = 0; i < a.rgb.size(); ++i)
      worst = std::max(worst, std::abs(b.rgb[i] - a.rgb[i]) / (a.rgb[i] + 1e-9f));
  }
  EXPECT_GT(worst, 0.1f) << "without the judgement, some merged value is the CPU's";
  EXPECT_THROW(lp::gl::GpuMerge({.groupSize = 100}), lp::gl::ContextError);
}

// The last merges' luminance kept on the GPU (merge::FrameInput::previousKey, referenceKey) is
// what the merge wrote, not what the caller's buffers hold: a merge told its previous and
// reference are the last merge's own (by key), handed buffers of garbage, sums as one handed that
// merge's luminance read back; handed the garbage under no key, it sums otherwise (the garbage is
// read, so the keys are what kept it out).
TEST(GpuMerge, KeptLuminanceIsTheLastMergesOwn) {
  eglContext().makeCurrent();
  constexpr int w = 125, h = 64;
  const auto frames = movingBracket(w, h, 4);
  const std::size_t pixels = std::size_t(w) * h;
  std::array<std::array<float, 256>, 3> lut{};
  for (auto& l : lut)
    for (int c = 0; c < 256; ++c) l[std::size_t(c)] = lp::srgbToLinear(float(c) / 255.0f);
  const auto input = [&](int newest, const float* previous, const float* reference,
                         float* luminance) {
    lp::merge::FrameInput in;
    in.frames = 3, in.width = w, in.height = h;
    for (int i = 0; i < 3; ++i) {
      const lp::Frame& f = frames[std::size_t(newest - 2 + i)];
      in.bgr[i] = f.bgr8.data(), in.scale[i] = float(f.radianceScale);
      if (in.scale[i] < in.scale[in.longest]) in.longest = i;
    }
    for (int c = 0; c < 3; ++c) in.lut[c] = lut[std::size_t(c)].data();
    in.floor = 6, in.clip = 250, in.wellExposed = 16;
    in.wellLinear = lut[1][16], in.belowClipLinear = lut[1][200];
    in.inv2s2 = float(1.0 / (2 * 0.3 * 0.3));
    in.previous = previous, in.reference = reference, in.luminance = luminance, in.fresh = true;
    return in;
  };
  const std::vector<float> zeros(pixels, 0.0f), garbage(pixels, 1e6f);
  std::vector<float> first(pixels), second(pixels), third(pixels);
  std::vector<lp::merge::RowSums> rows;
  const auto sums = [&](const std::vector<lp::merge::RowSums>& r) {
    double lost = 0, estimate = 0;
    for (const auto& s : r) lost += s.lostPower, estimate += s.clippedEstimate;
    return std::pair(lost, estimate);
  };
  lp::gl::GpuMerge kept, apart;
  lp::merge::FrameInput a = input(2, zeros.data(), zeros.data(), first.data());
  a.previousKey = a.referenceKey = 5, a.luminanceKey = 11;
  kept(a, rows);
  // The next merge: its previous and reference are the first's own, by key; the buffers lie.
  lp::merge::FrameInput b = input(3, garbage.data(), garbage.data(), second.data());
  b.previousKey = b.referenceKey = 11, b.luminanceKey = 12;
  kept(b, rows);
  const auto byKey = sums(rows);
  const std::size_t uploads = kept.luminanceUploaded();
  // The same merge handed the first's luminance as read back, under no key.
  lp::merge::FrameInput c = input(3, first.data(), first.data(), third.data());
  apart(c, rows);
  const auto handed = sums(rows);
  EXPECT_EQ(second, third);
  EXPECT_NEAR(byKey.first, handed.first, 1e-6 * (1 + handed.first));
  EXPECT_NEAR(byKey.second, handed.second, 1e-6 * (1 + handed.second));
  EXPECT_EQ(uploads, 1u) << "the first merge's buffers, once (previous and reference are one)";
  // The garbage, read: another answer.
  lp::merge::FrameInput d = input(3, garbage.data(), garbage.data(), third.data());
  apart(d, rows);
  EXPECT_GT(sums(rows).first, 10 * (1 + handed.first));
}

// The merged frame kept on the GPU for the drawing context (merge::FrameInput::rgbKept,
// gl::GpuImage): merged on another thread in a context that shares the drawing one's objects
// (ContextSpec::shareWith), as a stream's capture thread merges. Each kept frame, read in the
// drawing context, is the CPU's merged frame (1e-5), however many later merges ran while it was
// held (a held buffer is never written: one more is made); drawn as the background it is what the
// CPU's frame draws. Frames let go are written again (no more buffers); once the merge is gone, a
// frame still held reads nothing and the background stays as it was.
TEST(GpuMerge, AKeptFrameIsDrawnAsTheCpusMergedFrame) {
  lp::gl::GlContext& drawing = eglContext();
  drawing.makeCurrent();
  constexpr int w = 125, h = 64;
  const auto frames = movingBracket(w, h, 9);
  const lp::Projector projector(lp::Layout::Equirect, w, h);
  lp::gl::releaseCurrentContext();
  std::shared_ptr<lp::gl::GlContext> capture =
      lp::gl::createGlContext({.backend = lp::gl::Backend::Egl,
                               .width = 16,
                               .height = 16,
                               .title = "capture",
                               .vsync = false,
                               .gpu = drawing.device(),
                               .shareWith = &drawing});
  lp::gl::releaseCurrentContext();
  std::unique_ptr<lp::gl::GpuMerge> gpu;
  lp::BracketMerger cpu(lp::MergeOptions{.frames = 3}), onGpu(lp::MergeOptions{.frames = 3});
  std::vector<std::shared_ptr<const lp::gl::GpuImage>> kept;
  std::vector<std::vector<float>> expected;
  // Merges frames [first, last) on a thread of their own; `hold`: every kept frame is held.
  const auto mergeOnThread = [&](std::size_t first, std::size_t last, bool hold) {
    std::thread([&] {
      capture->makeCurrent();
      if (!gpu) {
        gpu = std::make_unique<lp::gl::GpuMerge>();
        onGpu.setFrameKernel([&](const lp::merge::FrameInput& in,
                                 std::vector<lp::merge::RowSums>& rows) { (*gpu)(in, rows); });
      }
      for (std::size_t i = first; i < last; ++i) {
        if (!hold) kept.clear(), expected.clear();
        lp::Frame a, b;
        // Every other merge's frame comes back too (as a light search reads it).
        const bool back = i % 2 == 1;
        lp::MergeProjection pa{.integrals = projector.equirectIntegrals()},
            pb{.integrals = projector.equirectIntegrals(),
               .keepFrame = back,
               .keepWhereMerged = true};
        cpu.add(frames[i], a, nullptr, pa);
        onGpu.add(frames[i], b, nullptr, pb);
        if (back) {
          ASSERT_EQ(b.rgb.size(), a.rgb.size()) << "frame " << i << ": kept and read back";
          for (std::size_t k = 0; k < a.rgb.size(); ++k)
            ASSERT_NEAR(b.rgb[k], a.rgb[k], 1e-5f * a.rgb[k] + 1e-9f) << "frame " << i;
        } else {
          EXPECT_TRUE(b.rgb.empty()) << "frame " << i << ": kept on the GPU, not read back";
        }
        kept.push_back(gpu->takeKeptImage());
        expected.push_back(a.rgb);
        EXPECT_FALSE(gpu->takeKeptImage()) << "handed over once";
      }
      lp::gl::releaseCurrentContext();
    }).join();
    drawing.makeCurrent();
  };
  // Reads a kept frame in the drawing context.
  const auto read = [](const lp::gl::GpuImage& image) {
    std::vector<float> rgb(std::size_t(image.width()) * image.height() * 3, -1.0f);
    const bool done = image.read([&](GLuint buffer) {
      glBindBuffer(GL_COPY_READ_BUFFER, buffer);
      glGetBufferSubData(GL_COPY_READ_BUFFER, 0, GLsizeiptr(rgb.size() * sizeof(float)),
                         rgb.data());
      glBindBuffer(GL_COPY_READ_BUFFER, 0);
    });
    return done ? rgb : std::vector<float>{};
  };
  const auto expectSame = [](const std::vector<float>& got, const std::vector<float>& want,
                             const std::string& what) {
    ASSERT_EQ(got.size(), want.size()) << what;
    for (std::size_t i = 0; i < want.size(); ++i)
      ASSERT_NEAR(got[i], want[i], 1e-5f * want[i] + 1e-9f) << what << " value " << i;
  };
  mergeOnThread(0, 6, true);
  ASSERT_EQ(kept.size(), 6u);
  EXPECT_EQ(gpu->keptBuffers(), 6u) << "each merge while the others were held: a buffer of its own";
  for (std::size_t i = 0; i < kept.size(); ++i) {
    ASSERT_TRUE(kept[i]);
    EXPECT_EQ(kept[i]->width(), w);
    EXPECT_EQ(kept[i]->height(), h);
    expectSame(read(*kept[i]), expected[i], "merge " + std::to_string(i));
  }
  // Drawn as the background, from the GPU and from the CPU's frame.
  lp::gl::Renderer r;
  const auto background = [&] {
    lp::gl::FloatTarget target(64, 32);
    target.bind();
    lp::gl::ShadingSettings s;
    s.toneMap = lp::gl::ToneMap::Linear;
    lp::gl::Camera cam;
    r.draw({64, 32}, cam, s);
    return target.readRgba();
  };
  r.setBackground(*kept[4], lp::gl::BackgroundMapping::Equirect, 1.0f);
  const auto fromGpu = background();
  r.setBackground(expected[4].data(), w, h, lp::gl::BackgroundMapping::Equirect);
  const auto fromCpu = background();
  expectSame(fromGpu, fromCpu, "the background");
  // Let go, the buffers are written again.
  mergeOnThread(6, 9, false);
  EXPECT_EQ(gpu->keptBuffers(), 6u);
  expectSame(read(*kept.back()), expected.back(), "merge 8");
  // The merge gone (on its thread, its context current; then the context too), a frame still
  // held is still drawn (the last frame of a stream, drawn after its merge ended), once: its
  // first read deletes its buffer, a second reads nothing.
  std::thread([&] {
    capture->makeCurrent();
    gpu.reset();
    lp::gl::releaseCurrentContext();
    capture.reset();
  }).join();
  drawing.makeCurrent();
  r.setBackground(*kept.back(), lp::gl::BackgroundMapping::Equirect, 1.0f);
  const auto lastFromGpu = background();
  EXPECT_TRUE(read(*kept.back()).empty()) << "read once";
  r.setBackground(expected.back().data(), w, h, lp::gl::BackgroundMapping::Equirect);
  expectSame(lastFromGpu, background(), "the last background, its maker gone");
  kept.clear();
}

// The older frames of a turning camera turned on the GPU (GpuMerge's turn, merge::FrameInput::turn)
// against the CPU's turn (align::turnCodes) and merge: quarry_01 at 256x128 turning 1 and 5
// degrees a frame about a tilted axis, shot at -13, -7 and 0 EV in turn (0 EV: the median at
// mid-grey). The GPU reads each pixel's source from the CPU's grid of sources, as the CPU
// interpolates it; a turned code may still round the other way (a multiply-add fused on one
// side): each merge's coefficients within 1e-4 of L00, its confidence within 1e-3, and at most
// 0.1% of the merged values 1% or more off the CPU's. The frames left out whole must be the
// CPU's too: judged on the older frames turned, not as taken (the checkerboard below).
TEST(GpuMerge, TurnedFramesMergeAsTheCpuTurnsThem) {
  eglContext().makeCurrent();
  const lp::Image full = lp::loadImage(lpt::dataPath("equirect/quarry_01_1k.hdr"));
  const lp::Image map = lp::reduceEquirect(full.rgb.data(), full.width, full.height, 4);
  std::vector<float> green;
  for (std::size_t i = 1; i < map.rgb.size(); i += 3) green.push_back(map.rgb[i]);
  std::nth_element(green.begin(), green.begin() + long(green.size() / 2), green.end());
  const double t0 = 0.18 / green[green.size() / 2];
  const double axis[3] = {0.57735, 0.57735, 0.57735};
  const lp::Projector projector(lp::Layout::Equirect, map.width, map.height);
  // A checkerboard of 8-pixel squares, 1:10, turning 2 degrees a frame (1.4 pixels), shot at -1,
  // 0 and +1 EV: the whole-frame check decides here (its readings well exposed in every frame).
  // The tracker reads the turn short, and the older frames, turned, contradict the newest: left
  // out whole, on both sides (judged as taken instead, they were kept and 9% to 62% of the
  // merged values differed from the CPU's).
  lp::Image checker = map;
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x)
      for (int c = 0; c < 3; ++c)
        checker
            .rgb[(std::size_t(y) * std::size_t(map.width) + std::size_t(x)) * 3 + std::size_t(c)] =
            ((x / 8 + y / 8) % 2) ? 2.0f : 0.2f;
  struct Case {
    const lp::Image* scene;
    double degPerFrame;
    std::array<int, 3> ev;
    bool merged;  ///< turned older frames reach the merge
  };
  for (const Case& cs : {Case{&map, 1.0, {-13, -7, 0}, true}, Case{&map, 5.0, {-13, -7, 0}, true},
                         Case{&checker, 2.0, {-1, 0, 1}, false}}) {
    const double degPerFrame = cs.degPerFrame;
    lp::gl::GpuMerge gpu;
    lp::BracketMerger cpu(lp::MergeOptions{.frames = 3}), onGpu(lp::MergeOptions{.frames = 3});
    bool turnedSome = false;
    std::size_t fetched = 0;
    onGpu.setFrameKernel(
        [&](const lp::merge::FrameInput& in, std::vector<lp::merge::RowSums>& rows) {
          for (int i = 0; i < in.frames; ++i) turnedSome = turnedSome || in.turn[i].apply;
          gpu(in, rows);
        },
        true,
        [&](std::uint64_t key, float* into) { return ++fetched, gpu.readLuminance(key, into); });
    for (int n = 0; n < 12; ++n) {
      const lp::Image now = lpt::turnedMap(*cs.scene, axis, n * degPerFrame);
      const double t = t0 * std::exp2(cs.ev[std::size_t(n % 3)]);
      lp::Frame f;
      f.format = lp::PanoramaFormat::BgrU8;
      f.width = now.width, f.height = now.height, f.sequence = std::uint64_t(n);
      f.radianceScale = 1.0 / t;
      f.bgr8.resize(now.rgb.size());
      for (std::size_t i = 0; i < now.rgb.size(); i += 3)
        for (std::size_t c = 0; c < 3; ++c)
          f.bgr8[i + 2 - c] = std::uint8_t(std::lround(
              255.0f * lp::linearToSrgb(std::clamp(float(now.rgb[i + c] * t), 0.0f, 1.0f))));
      lp::Frame a, b;
      lp::MergeProjection pa{.integrals = projector.equirectIntegrals()}, pb = pa;
      const lp::FrameConfidence ca = cpu.add(f, a, nullptr, pa), cb = onGpu.add(f, b, nullptr, pb);
      double worst = 0;
      for (int k = 0; k < lp::kShCount; ++k)
        for (int c = 0; c < 3; ++c)
          worst =
              std::max(worst, double(std::abs(pb.coefficients.c[k][c] - pa.coefficients.c[k][c])));
      worst /= pa.coefficients.c[0][1];
      std::size_t off = 0;
      for (std::size_t i = 0; i < a.rgb.size(); ++i)
        off += std::abs(b.rgb[i] - a.rgb[i]) >= 0.01f * a.rgb[i] + 1e-9f;
      std::printf(
          "%g degrees a frame, frame %d: coefficients within %.2g of L00, confidence %.4f against "
          "%.4f (complete %d, %d), %zu of %zu values 1%% off\n",
          degPerFrame, n, worst, cb.value(), ca.value(), cb.complete, ca.complete, off,
          a.rgb.size());
      const std::string what = std::to_string(degPerFrame) + " degrees, frame " + std::to_string(n);
      EXPECT_LT(worst, 1e-4) << what;
      EXPECT_NEAR(cb.value(), ca.value(), 1e-3) << what;
      EXPECT_EQ(cb.complete, ca.complete) << what;
      EXPECT_LE(off, a.rgb.size() / 1000) << what;
    }
    EXPECT_EQ(turnedSome, cs.merged) << degPerFrame << " degrees: turned frames merged";
    // The last merges' luminance, kept on the GPU, read back to be turned on the CPU.
    EXPECT_GT(fetched, 0u) << degPerFrame << " degrees";
  }
}

}  // namespace
