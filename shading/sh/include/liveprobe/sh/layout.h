#pragma once
// Panorama layouts: how each maps its pixels to directions in the R&H world frame of
// liveprobe/sh/sh.h (+z up; p from +x towards +y), and the exact solid angle of every pixel.
// Every layout's "front" is world -x and its "up" is world +z, so the same scene gives the
// same coefficients in every layout (tested), and the default view (liveprobe/sh/axes.h) looks at
// it.
//
// equirect (latitude-longitude), any W x H (defined in liveprobe/sh/sh.h):
//   row i    -> t in [pi i/H, pi (i+1)/H]     (row 0 is next to +z, the zenith)
//   column j -> p in [2 pi j/W, 2 pi (j+1)/W] (the centre column looks along -x)
//   projected with exact per-pixel integrals of the basis.
//
// angular (Debevec light-probe map), W x W, pixel centres:
//   u = (j + 0.5 - W/2)/(W/2), v = (W/2 - i - 0.5)/(W/2), r = sqrt(u^2 + v^2) (r > 1: nothing)
//   local direction (R&H's prefilter frame, sh-notes.md): t = pi r, p = atan2(v, u),
//   l = (sin t cos p, sin t sin p, cos t): l.z is the map centre, l.x image right, l.y image up.
//   World = angularToWorld(l) = (-l.z, -l.x, l.y): the centre looks along -x (the equirect's
//   centre column), image up is +z, image right is -y (right of the equirect's centre column).
//   R&H's published table is in the local frame (rotate by worldToAngular to compare).
//   dw = integral of pi sin(pi r)/r du dv over the pixel clipped to the disc, by sub-samples
//   (8x8 on the rim, 2x2 inside), then scaled to sum to exactly 4 pi (a correction below 1e-4
//   for W >= 64).
//
// mirrorball: a photo of a chrome sphere, any frame size, the ball's circle given in pixels
//   (LayoutSpec::circle: cx, cy, r). The angular map's frame with t = 2 asin(r) instead of pi r:
//   the ball's centre reflects the direction back towards the camera, which this frame calls the
//   front (-x). dw = 4 (pixel area inside the circle) / R^2: uniform, since d(omega) = 4 r dr dp.
//   That is the ball seen from infinitely far. With LayoutSpec::lens (the camera's calibration,
//   liveprobe/capture/lens.h's makeBallModel) each pixel's ray is traced to the ball at the
//   distance its circle implies and reflected, in the same world (the ray to the ball's centre
//   +x); the cone behind the ball and the camera's own reflection are unseen.
//
// cube (OpenGL's face convention; a horizontal 4:3 cross or a vertical 3:4 cross):
//        [+Y]                     [+Y]
//   [-X] [+Z] [+X] [-Z]      [-X] [+Z] [+X]
//        [-Y]                     [-Y]
//                                 [-Z]  (rotated 180 degrees)
//   Within a face (N x N), s = (j + 0.5)/N, t = (i + 0.5)/N (row 0 at the top of the file), and
//   the direction in GL's frame is the GL specification's table (e.g. +X: (1, -(2t-1), -(2s-1)),
//   +Z: (2s-1, -(2t-1), 1)), turned into the world by liveprobe/sh/axes.h (world = (Z, -X, Y)), the
//   same map that shows a GL cube-map texture in liveprobe's viewer. Six separate face files
//   (px, nx, py, ny, pz, nz) are assembled into a horizontal cross by the source.
//   dw is exact: F(a1,b1) - F(a0,b1) - F(a1,b0) + F(a0,b0), F(a, b) = atan2(ab, sqrt(a^2+b^2+1)).
//   Cells of the cross outside the six faces carry nothing.
//
// fisheye (dual fisheye, two equidistant circles side by side in a 2:1 frame): the left circle
//   is the front lens (axis -x), the right circle the back lens (axis +x); each circle's centre
//   is the centre of its half, its radius H/2, and it spans `fov` degrees (default 190):
//   polar angle from the lens axis = (rho / R) * fov/2. Image up is +z in both; image right is
//   -y in the front lens and +y in the back lens (as seen from inside, like the equirect).
//   Where the lenses overlap (polar angle in [180 - fov/2, fov/2]) each pixel is weighted by a
//   linear feather that falls from 1 to 0 across the band; the two weights sum to 1 for every
//   direction. dw = (fov/2 / R)^2 sin(theta)/theta per pixel area, times that weight.
//
// lens: a calibrated camera (LayoutSpec::lens, a LensModel; liveprobe/capture/lens.h makes one
//   from a calibration through OpenCV). A direction in OpenCV's camera frame (x right, y down,
//   z along the optical axis) is the same vector in the world frame: a camera looking straight up
//   sees the zenith at its centre. dw is the pixel's own solid angle on the sphere, 0 where the
//   lens sees nothing.
//
// What a layout does not see (a lens's unseen cone; coverage below 1) is filled by
// LayoutSpec::unseen when frames are projected (liveprobe/sh/projector.h).
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "liveprobe/sh/sh.h"

namespace lp {

enum class Layout : std::uint8_t { Equirect, Angular, MirrorBall, Cube, DualFisheye, Lens };

std::string_view layoutName(Layout layout);
/// Parses equirect|angular|mirrorball|cube|fisheye|lens; throws lp::Error naming the bad value.
Layout parseLayout(std::string_view name);

/// A real camera's lens as the core sees it: where each pixel of a frame looks, and back. The
/// core knows no lens model; liveprobe/capture/lens.h implements this from a calibration.
class LensModel {
 public:
  virtual ~LensModel() = default;
  /// Empty when a W x H frame is this lens's; otherwise why not, in words.
  virtual std::string mismatch(int width, int height) const = 0;
  /// Empty when a W x H frame is the lens as calibrated; a note, in words, when it is the lens
  /// scaled (a camera mode of the same aspect at another size).
  virtual std::string scaling(int width, int height) const = 0;
  /// One sample per pixel of a W x H frame, row-major: the world direction of the pixel's centre
  /// and its solid angle on the sphere (0 where the lens sees nothing).
  virtual std::vector<SphereSample> samples(int width, int height) const = 0;
  /// Where each of `count` world directions lands in a W x H frame, in pixel coordinates (x
  /// right, y down, pixel centres at +0.5); NaN where the lens does not see it.
  virtual void pixels(int width, int height, const glm::vec3* dirs, std::size_t count,
                      glm::vec2* out) const = 0;
  /// What the lens is, for messages: its model and where it came from.
  virtual std::string describe() const = 0;
};

/// What fills the directions a frame does not see (the share 1 - coverage of the sphere).
struct UnseenRule {
  enum class Fill : std::uint8_t {
    Ground,  ///< below the horizon a Lambertian ground, L = albedo E_up / pi, lit by what is
             ///< seen above it; unseen directions above the horizon take the nearest seen pixel
    Mean,    ///< the mean radiance of the edge of what is seen
    Black,   ///< nothing
  };
  Fill fill = Fill::Ground;
  float albedo = 0.2f;  ///< Ground: the ground's reflectance (grass and asphalt: about 0.2)
  /// Ground: the world's up as a direction of the frame's own (where the frame is turned into
  /// the world, liveprobe/capture/frame_processor.h sets it from the turn).
  glm::vec3 up{0.0f, 0.0f, 1.0f};
};
std::string unseenName(const UnseenRule& rule);
/// Parses ground[=ALBEDO]|mean|black; throws lp::Error naming the bad value.
UnseenRule parseUnseen(std::string_view text);

/// A layout with its parameters.
struct LayoutSpec {
  Layout layout = Layout::Equirect;
  glm::vec3 circle{0.0f};  ///< mirrorball: centre x, centre y, radius, in pixels (r = 0: unset)
  float fisheyeFovDeg = 190.0f;  ///< fisheye: field of view of each lens
  /// lens: the camera's lens; mirrorball: the ball traced through the camera's lens
  std::shared_ptr<const LensModel> lens;
  UnseenRule unseen;  ///< what fills the directions the frame does not see

  LayoutSpec() = default;
  LayoutSpec(Layout l) : layout(l) {}  // NOLINT: a bare layout is a spec with default parameters
};

/// Empty when a W x H frame can hold the layout; otherwise why not, in words.
std::string layoutMismatch(const LayoutSpec& spec, int width, int height);

/// One SphereSample per pixel, row-major, for a W x H frame. Throws lp::Error if the frame does
/// not fit the layout.
std::vector<SphereSample> layoutSamples(const LayoutSpec& spec, int width, int height);

/// Angular-map local frame <-> world frame (a proper rotation).
inline glm::vec3 angularToWorld(glm::vec3 l) { return {-l.z, -l.x, l.y}; }
inline glm::vec3 worldToAngular(glm::vec3 w) { return {-w.y, w.z, -w.x}; }

/// Equirect sample centres: unit normals at the pixel centres of a W x H grid, row-major, and
/// their exact solid angles. Used for output irradiance maps.
std::vector<SphereSample> equirectSamples(int width, int height);

/// The world direction of point (s, t) in [0, 1]^2 of OpenGL cube face `face` (0..5: +X, -X, +Y,
/// -Y, +Z, -Z; t = 0 is the face's first row), as the cube layout above defines it. Not normalised.
glm::vec3 cubeFaceDirection(int face, double s, double t);

/// Where the world direction `dir` lands in a W x H frame of the layout, in pixel coordinates
/// (x right, y down, pixel centres at +0.5), or nullopt where the layout does not see it. The
/// inverse of layoutSamples' directions (for resampling, backgrounds and tests).
std::optional<glm::vec2> layoutPixel(const LayoutSpec& spec, int width, int height, glm::vec3 dir);
/// layoutPixel for `count` directions at once (a lens asks its model once for all); NaN where the
/// layout does not see a direction.
void layoutPixels(const LayoutSpec& spec, int width, int height, const glm::vec3* dirs,
                  std::size_t count, glm::vec2* out);

}  // namespace lp
