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
#include <vector>

#include "liveprobe/capture/lens.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/gl/gpu_projector.h"
#include "liveprobe/gl/gpu_timer.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/projector.h"
#include "test_util.h"

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

}  // namespace
