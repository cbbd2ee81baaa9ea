#include "liveprobe/capture/photometry.h"

#include <cmath>

namespace lp {

Linearizer::Linearizer(const Photometry& p) : exposure_(p.exposure) {
  for (int i = 0; i < 256; ++i) {
    const float v = i / 255.0f;
    lut_[i] = p.exposure * (p.gamma > 0.0f ? std::pow(v, p.gamma) : srgbToLinear(v));
  }
}

std::size_t Linearizer::convert(const Frame& frame, Image& out) const {
  out.width = frame.width;
  out.height = frame.height;
  const std::size_t n = std::size_t(frame.width) * frame.height;
  out.rgb.resize(n * 3);
  if (frame.format == PanoramaFormat::RgbF32) {
    if (exposure_ == 1.0f) {
      std::copy(frame.rgb.begin(), frame.rgb.end(), out.rgb.begin());
    } else {
      for (std::size_t i = 0; i < n * 3; ++i) out.rgb[i] = frame.rgb[i] * exposure_;
    }
    return 0;
  }
  std::size_t saturated = 0;
  const std::uint8_t* s = frame.bgr8.data();
  float* d = out.rgb.data();
  for (std::size_t i = 0; i < n; ++i, s += 3, d += 3) {
    d[0] = lut_[s[2]];
    d[1] = lut_[s[1]];
    d[2] = lut_[s[0]];
    saturated += (s[0] == 255) + (s[1] == 255) + (s[2] == 255);
  }
  return saturated;
}

std::size_t countSaturated(const Frame& frame) {
  if (frame.format != PanoramaFormat::BgrU8) return 0;
  std::size_t n = 0;  // channel values at 255 (a byte count vectorises; pixels would not)
  for (const std::uint8_t v : frame.bgr8) n += v == 255;
  return n;
}

}  // namespace lp
