#pragma once
// Pixel -> world direction for every layout, from the conventions in liveprobe/sh/layout.h
// written out again by the tests (not the library's code): each returns, for a point (x, y) in
// pixel coordinates (pixel centres at +0.5), the direction it sees, or nothing outside the image.
#include <cmath>
#include <functional>
#include <glm/glm.hpp>
#include <numbers>
#include <optional>

#include "liveprobe/sh/layout.h"

namespace lpt {

using DirAt = std::function<std::optional<glm::dvec3>(double x, double y)>;

inline glm::dvec3 lensLocal(double t, double p) {
  return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

inline DirAt equirectDirs(int w, int h) {
  return [=](double x, double y) -> std::optional<glm::dvec3> {
    return lensLocal(std::numbers::pi * y / h, 2 * std::numbers::pi * x / w);
  };
}

inline DirAt angularDirs(int w) {
  return [=](double x, double y) -> std::optional<glm::dvec3> {
    const double u = (x - w / 2.0) / (w / 2.0), v = (w / 2.0 - y) / (w / 2.0), r = std::hypot(u, v);
    if (r > 1) return std::nullopt;
    const glm::dvec3 l = lensLocal(std::numbers::pi * r, std::atan2(v, u));
    return glm::dvec3(-l.z, -l.x, l.y);
  };
}

inline DirAt mirrorBallDirs(double cx, double cy, double R) {
  return [=](double x, double y) -> std::optional<glm::dvec3> {
    const double u = (x - cx) / R, v = (cy - y) / R, r = std::hypot(u, v);
    if (r > 1) return std::nullopt;
    const glm::dvec3 l = lensLocal(2 * std::asin(r), std::atan2(v, u));
    return glm::dvec3(-l.z, -l.x, l.y);
  };
}

// OpenGL's face table, and the world = (Z, -X, Y) map of liveprobe/sh/axes.h.
inline glm::dvec3 glFace(int face, double s, double t) {
  const double sc = 2 * s - 1, tc = 2 * t - 1;
  const glm::dvec3 g[6] = {{1, -tc, -sc}, {-1, -tc, sc}, {sc, 1, tc},
                           {sc, -1, -tc}, {sc, -tc, 1},  {-sc, -tc, -1}};
  const glm::dvec3 r = glm::normalize(g[face]);
  return {r.z, -r.x, r.y};
}

/// A 4n x 3n horizontal cross, or (vertical) a 3n x 4n one with -Z below -Y turned 180 degrees.
inline DirAt cubeCrossDirs(int n, bool vertical) {
  // Horizontal: +Y at (1,0); -X,+Z,+X,-Z on row 1; -Y at (1,2).
  static constexpr int hc[6][2] = {{2, 1}, {0, 1}, {1, 0}, {1, 2}, {1, 1}, {3, 1}};
  static constexpr int vc[6][2] = {{2, 1}, {0, 1}, {1, 0}, {1, 2}, {1, 1}, {1, 3}};
  return [=](double x, double y) -> std::optional<glm::dvec3> {
    const auto& cells = vertical ? vc : hc;
    for (int f = 0; f < 6; ++f)
      if (int(x / n) == cells[f][0] && int(y / n) == cells[f][1]) {
        double s = x / n - cells[f][0], t = y / n - cells[f][1];
        if (vertical && f == 5) s = 1 - s, t = 1 - t;
        return glFace(f, s, t);
      }
    return std::nullopt;
  };
}

/// Two equidistant circles side by side in a w x h frame (w = 2h), each spanning fovDeg.
inline DirAt dualFisheyeDirs(int w, int h, float fovDeg) {
  const double half = glm::radians(double(fovDeg)) / 2, R = h / 2.0;
  return [=](double x, double y) -> std::optional<glm::dvec3> {
    const bool front = x < w / 2.0;
    const double u = (x - (front ? w / 4.0 : 3 * w / 4.0)) / R, v = (h / 2.0 - y) / R,
                 r = std::hypot(u, v);
    if (r > 1) return std::nullopt;
    const glm::dvec3 l = lensLocal(r * half, std::atan2(v, u));  // (right, up, forward)
    return front ? glm::dvec3(-l.z, -l.x, l.y) : glm::dvec3(l.z, l.x, l.y);
  };
}

}  // namespace lpt
