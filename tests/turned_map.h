#pragma once
// Moving scenes for the HDR tests: a map of ../shared/data reduced to a camera's size and turned
// a little more every frame about any axis (a camera on a turning rig, a vehicle, a hand), saved
// as float frames the emulated camera renders. Directions follow liveprobe's equirect convention
// (liveprobe/sh/layout.h: row 0 next to +z, the centre column along -x).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "liveprobe/capture/image.h"
#include "liveprobe/capture/resample.h"

namespace lpt {

/// `src` (equirect) turned by `deg` degrees about the unit `axis` (right-handed), resampled
/// bilinearly at its own size: the scene's direction d is seen at R d.
inline lp::Image turnedMap(const lp::Image& src, const double axis[3], double deg) {
  const int w = src.width, h = src.height;
  const double a = deg * M_PI / 180.0, c = std::cos(a), s = std::sin(a);
  const double x = axis[0], y = axis[1], z = axis[2];
  // Rodrigues' rotation matrix; its transpose takes a seen direction back to the scene's.
  const double r[3][3] = {{c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s},
                          {y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s},
                          {z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)}};
  lp::Image out(w, h);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) {
      const double t = M_PI * (i + 0.5) / h, p = 2 * M_PI * (j + 0.5) / w;
      const double d[3] = {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
      double q[3];
      for (int k = 0; k < 3; ++k) q[k] = r[0][k] * d[0] + r[1][k] * d[1] + r[2][k] * d[2];
      const double ts = std::acos(std::clamp(q[2], -1.0, 1.0));
      double ps = std::atan2(q[1], q[0]);
      if (ps < 0) ps += 2 * M_PI;
      const double fx = ps / (2 * M_PI) * w - 0.5,
                   fy = std::clamp(ts / M_PI * h - 0.5, 0.0, h - 1.0);
      const int x0 = int(std::floor(fx)), y0 = std::min(int(fy), h - 2);
      const double ax = fx - x0, ay = fy - y0;
      for (int k = 0; k < 3; ++k) {
        auto at = [&](int yy, int xx) { return double(src.pixel(((xx % w) + w) % w, yy)[k]); };
        out.pixel(j, i)[k] = float((1 - ay) * ((1 - ax) * at(y0, x0) + ax * at(y0, x0 + 1)) +
                                   ay * ((1 - ax) * at(y0 + 1, x0) + ax * at(y0 + 1, x0 + 1)));
      }
    }
  return out;
}

/// `frames` float frames of `map` (equirect, reduced by `reduce`) turning `degPerFrame` about
/// `axis`, written as dir/0000.exr, ...; their paths.
inline std::vector<std::string> turningFrames(const std::string& map, int reduce,
                                              const double axis[3], double degPerFrame, int frames,
                                              const std::filesystem::path& dir) {
  const lp::Image full = lp::loadImage(map);
  const lp::Image small = lp::reduceEquirect(full.rgb.data(), full.width, full.height, reduce);
  std::filesystem::create_directories(dir);
  std::vector<std::string> paths;
  for (int n = 0; n < frames; ++n) {
    char name[32];
    std::snprintf(name, sizeof name, "%04d.exr", n);
    paths.push_back((dir / name).string());
    lp::saveImage(paths.back(), turnedMap(small, axis, n * degPerFrame));
  }
  return paths;
}

}  // namespace lpt
