#pragma once
// Panorama layouts: how each maps its pixels to directions in the R&H world frame of
// shading/sh.h (+z up; p from +x towards +y), and the exact solid angle of every pixel.
//
// equirect (latitude-longitude), any W x H:
//   row i    -> t = pi (i + 0.5) / H     (row 0 is next to +z, the zenith)
//   column j -> p = 2 pi (j + 0.5) / W   (the centre column looks along -x)
//   dw = (2 pi / W)(cos t0 - cos t1), t0 and t1 the row's edges; exact; sums to 4 pi.
//
// angular (Debevec light-probe map), W x W, pixel centres:
//   u = (j + 0.5 - W/2)/(W/2), v = (W/2 - i - 0.5)/(W/2), r = sqrt(u^2 + v^2) (r > 1: nothing)
//   local direction (R&H's prefilter frame, sh-notes.md): t = pi r, p = atan2(v, u),
//   l = (sin t cos p, sin t sin p, cos t): l.z is the map centre, l.x image right, l.y image up.
//   World = angularToWorld(l) = (-l.z, -l.x, l.y): the centre looks along -x (the equirect's
//   centre column), image up is +z, image right is -y (right of the equirect's centre column).
//   So an angular map and the equirect of the same scene give the same coefficients. R&H's
//   published table is in the local frame (rotate by worldToAngular to compare term by term).
//   dw = integral of pi sin(pi r)/r du dv over the pixel clipped to the disc (the pixel-centre
//   value is (2 pi/W)^2 sin t / t), by 8x8 sub-samples, then scaled to sum to exactly 4 pi
//   (the correction is below 1e-4 for W >= 64; tested).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "shading/sh.h"

namespace lp {

enum class Layout : std::uint8_t { Equirect, Angular };

std::string_view layoutName(Layout layout);
/// Parses "equirect" or "angular"; throws lp::Error naming the bad value.
Layout parseLayout(std::string_view name);

/// Empty when a W x H frame can hold `layout`; otherwise why not ("angular map must be square").
std::string layoutMismatch(Layout layout, int width, int height);

/// One SphereSample per pixel, row-major, for a W x H frame. Throws lp::Error if the frame does
/// not fit the layout.
std::vector<SphereSample> layoutSamples(Layout layout, int width, int height);

/// Angular-map local frame <-> world frame (a proper rotation).
inline glm::vec3 angularToWorld(glm::vec3 l) { return {-l.z, -l.x, l.y}; }
inline glm::vec3 worldToAngular(glm::vec3 w) { return {-w.y, w.z, -w.x}; }

/// Equirect sample centres: unit normals at the pixel centres of a W x H grid, row-major, and
/// their exact solid angles. Used for output irradiance maps.
std::vector<SphereSample> equirectSamples(int width, int height);

}  // namespace lp

namespace lp {

/// Projects frames of one (layout, size) to radiance coefficients. The per-pixel directions and
/// solid angles (or, for equirect, the exact separable row/column integrals) are computed once
/// here and reused for every frame.
class Projector {
 public:
  /// Throws lp::Error if the frame size does not fit the layout.
  Projector(Layout layout, int width, int height);
  Layout layout() const { return layout_; }
  int width() const { return width_; }
  int height() const { return height_; }
  /// rgb: linear RGB floats, 3 per pixel, rows `rowStride` floats apart (0 = packed).
  Sh9 project(const float* rgb, std::size_t rowStride = 0) const;
  /// The per-pixel samples (directions and solid angles), row-major.
  const std::vector<SphereSample>& samples() const { return samples_; }

 private:
  Layout layout_;
  int width_, height_;
  std::vector<SphereSample> samples_;
  std::optional<EquirectProjector> equirect_;
};

}  // namespace lp
