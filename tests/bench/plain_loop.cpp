// Per row sin t, cos t and the row's solid angle per pixel, per column sin p and cos p (tables made
// once); per pixel the direction from them, the nine basis values with R&H's constants, and 27
// multiply-adds into float sums. One thread; whatever the compiler makes of it with -O3
// -march=native -ffast-math is the yardstick.
#include "plain_loop.h"

#include <cmath>
#include <numbers>

namespace lpbench {

PlainEquirect::PlainEquirect(int width, int height) : width_(width), height_(height) {
  const double pi = std::numbers::pi;
  for (int i = 0; i < height; ++i) {
    const double t = pi * (i + 0.5) / height;
    sinT_.push_back(float(std::sin(t)));
    cosT_.push_back(float(std::cos(t)));
    rowAngle_.push_back(
        float(2 * pi / width * (std::cos(pi * i / height) - std::cos(pi * (i + 1) / height))));
  }
  for (int j = 0; j < width; ++j) {
    const double p = 2 * pi * (j + 0.5) / width;
    sinP_.push_back(float(std::sin(p)));
    cosP_.push_back(float(std::cos(p)));
  }
}

std::array<float, 27> PlainEquirect::project(const float* rgb) const {
  std::array<float, 27> acc{};
  for (int i = 0; i < height_; ++i) {
    const float st = sinT_[std::size_t(i)], z = cosT_[std::size_t(i)],
                dw = rowAngle_[std::size_t(i)];
    const float* row = rgb + 3 * std::size_t(i) * std::size_t(width_);
    for (int j = 0; j < width_; ++j) {
      const float x = st * cosP_[std::size_t(j)], y = st * sinP_[std::size_t(j)];
      const float b[9] = {0.282095f,
                          0.488603f * y,
                          0.488603f * z,
                          0.488603f * x,
                          1.092548f * x * y,
                          1.092548f * y * z,
                          0.315392f * (3 * z * z - 1),
                          1.092548f * x * z,
                          0.546274f * (x * x - y * y)};
      const float* p = row + 3 * std::size_t(j);
      for (int k = 0; k < 9; ++k) {
        const float w = b[k] * dw;
        acc[std::size_t(3 * k)] += w * p[0];
        acc[std::size_t(3 * k + 1)] += w * p[1];
        acc[std::size_t(3 * k + 2)] += w * p[2];
      }
    }
  }
  return acc;
}

}  // namespace lpbench
