#pragma once
// A test scene shared by the SH core's tests and the comparison's: an equirect holding one small
// disc of constant radiance (a near-directional light), with its exact power.
#include <cmath>
#include <glm/glm.hpp>
#include <numbers>

#include "liveprobe/sh/image.h"

namespace lpt {

// Equirect with a small disc of constant radiance around `dir` (unit, R&H frame). Returns the
// disc's power (sum of L dw over its pixels) through `power`.
inline lp::Image discEquirect(int w, int h, glm::dvec3 dir, double radiusRad, float radiance,
                              double* power) {
  lp::Image img(w, h);
  *power = 0;
  const double cosR = std::cos(radiusRad);
  for (int i = 0; i < h; ++i) {
    const double t = std::numbers::pi * (i + 0.5) / h;
    const double dw =
        2 * std::numbers::pi / w *
        (std::cos(std::numbers::pi * i / h) - std::cos(std::numbers::pi * (i + 1) / h));
    for (int j = 0; j < w; ++j) {
      const double p = 2 * std::numbers::pi * (j + 0.5) / w;
      const glm::dvec3 d(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
      if (glm::dot(d, dir) >= cosR) {
        float* px = img.pixel(j, i);
        px[0] = px[1] = px[2] = radiance;
        *power += radiance * dw;
      }
    }
  }
  return img;
}

}  // namespace lpt
