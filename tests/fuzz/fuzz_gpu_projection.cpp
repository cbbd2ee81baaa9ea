// libFuzzer target: the GPU projection's inputs on an EGL context (Mesa's llvmpipe here): any
// layout, size, rows per group, pixel type and pixels. The bytes say, in order: the layout (and a
// mirror ball's circle, a fisheye's field of view), the pixel type, the width and height (1 to
// 512), the rows per group, then the pixels (repeated to fill the frame). Pixels are finite and
// non-negative: 8-bit codes through a gamma table, half floats with their exponent kept below
// infinity's, floats from 16 bits. Any input ends in lp::Error from both projectors (a size the
// layout cannot take) or in the GPU's coefficients within 1e-4 of L00 of the CPU's.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

#include "liveprobe/gl/context.h"
#include "liveprobe/gl/gpu_projector.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/projector.h"

namespace {

std::unique_ptr<lp::gl::GlContext> context;

struct Reader {
  const std::uint8_t* data;
  std::size_t size, at = 0;
  std::uint8_t byte() { return at < size ? data[at++] : 0; }
  int u16() { return byte() | (byte() << 8); }
};

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  context = lp::gl::createGlContext({lp::gl::Backend::Egl, 16, 16, "fuzz", false});
  if (!lp::gl::hasCompute()) std::abort();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in{data, size};
  lp::LayoutSpec spec;
  switch (in.byte() % 5) {
    case 0:
      spec = lp::LayoutSpec(lp::Layout::Equirect);
      break;
    case 1:
      spec = lp::LayoutSpec(lp::Layout::Angular);
      break;
    case 2:
      spec = lp::LayoutSpec(lp::Layout::MirrorBall);
      spec.circle = {float(in.u16() % 600), float(in.u16() % 600), float(in.u16() % 600)};
      break;
    case 3:
      spec = lp::LayoutSpec(lp::Layout::Cube);
      break;
    default:
      spec = lp::LayoutSpec(lp::Layout::DualFisheye);
      spec.fisheyeFovDeg = float(in.u16() % 400);
      break;
  }
  const lp::PanoramaFormat formats[] = {lp::PanoramaFormat::RgbF32, lp::PanoramaFormat::RgbF16,
                                        lp::PanoramaFormat::RgbU8, lp::PanoramaFormat::BgrU8};
  const lp::PanoramaFormat format = formats[in.byte() % 4];
  const int w = 1 + in.u16() % 512, h = 1 + in.u16() % 512, rows = in.byte();
  const std::size_t n = std::size_t(w) * std::size_t(h) * 3;
  std::vector<float> f32;
  std::vector<std::uint16_t> f16;
  std::vector<std::uint8_t> u8;
  const std::size_t first = in.at, left = size > in.at ? size - in.at : 0;
  auto at = [&](std::size_t i) { return left ? data[first + i % left] : std::uint8_t(0); };
  const void* pixels = nullptr;
  if (format == lp::PanoramaFormat::RgbF32) {
    f32.resize(n);
    for (std::size_t i = 0; i < n; ++i) f32[i] = float(at(2 * i) | (at(2 * i + 1) << 8)) / 64.0f;
    pixels = f32.data();
  } else if (format == lp::PanoramaFormat::RgbF16) {
    f16.resize(n);
    for (std::size_t i = 0; i < n; ++i)  // sign 0, exponent 0..30: finite, non-negative
      f16[i] = std::uint16_t(std::min((at(2 * i) | (at(2 * i + 1) << 8)) & 0x7fff, 0x7bff));
    pixels = f16.data();
  } else {
    u8.resize(n);
    for (std::size_t i = 0; i < n; ++i) u8[i] = at(i);
    pixels = u8.data();
  }
  std::array<float, 256> decode;
  for (int c = 0; c < 256; ++c) decode[std::size_t(c)] = std::pow(c / 255.0f, 2.2f) * 4.0f;
  const bool codes = format == lp::PanoramaFormat::RgbU8 || format == lp::PanoramaFormat::BgrU8;
  const lp::PanoramaView view{pixels, format, w, h, 0, spec, codes ? decode.data() : nullptr};

  std::unique_ptr<lp::Projector> cpu;
  std::unique_ptr<lp::gl::GpuProjector> gpu;
  bool cpuRefused = false, gpuRefused = false;
  try {
    cpu = std::make_unique<lp::Projector>(spec, w, h);
  } catch (const lp::Error&) {
    cpuRefused = true;
  }
  try {
    gpu = std::make_unique<lp::gl::GpuProjector>(spec, w, h, rows);
  } catch (const lp::Error&) {
    gpuRefused = true;
  }
  if (cpuRefused != gpuRefused) std::abort();  // one refuses a size the other takes
  if (cpuRefused) return 0;
  lp::gl::FrameTexture texture;
  texture.upload(view);
  const lp::Sh9 want = cpu->project(view);
  const lp::Sh9 got = gpu->project(texture, view.decode, format == lp::PanoramaFormat::BgrU8);
  const double scale =
      std::max({std::abs(want.c[0].x), std::abs(want.c[0].y), std::abs(want.c[0].z)});
  for (int k = 0; k < lp::kShCount; ++k)
    for (int c = 0; c < 3; ++c) {
      const double g = got.c[k][c], e = want.c[k][c];
      if (!std::isfinite(g) || std::abs(g - e) > 1e-4 * scale + 1e-6) std::abort();
    }
  return 0;
}
