#include "liveprobe/frame/frame.h"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "liveprobe/frame/srgb.h"

namespace lp {

double monotonicSeconds() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

std::string formatFps(double fps) {
  char text[64];
  std::snprintf(text, sizeof text, "%.4g fps", fps);
  return text;
}

float srgbToLinear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}
float linearToSrgb(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

}  // namespace lp
