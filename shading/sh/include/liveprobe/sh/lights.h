#pragma once
// Sun and sky: the dominant compact sources of a panorama (the sun, a lamp, a bright window),
// taken out of the nine coefficients and kept as small disc lights. Nine coefficients cannot
// follow a small bright source (R&H's worst case, a directional light, is off by 3/32 of the total
// intensity); a light of its own, added to the coefficients of the rest, is exact for it.
//
// The split conserves energy exactly: a pixel of the source keeps min(L, fill) in the residual
// and gives max(L - fill, 0) to the light, so residual + lights = the whole map.
//
// Extraction, per light (in the R&H world frame of liveprobe/sh/sh.h; all angles are between
// pixel directions, so it is the same for every layout):
//   1. the peak: the pixel with the largest linear channel value (Projector::project's row peaks);
//   2. the core: pixels near the peak whose luminance is at least coreFraction of the peak's
//      (when the peak is clipped, an 8-bit frame at its maximum, whose true brightness is
//      unknown: the clipped pixels, those with a channel at the maximum),
//      searched in caps of growing reach (1, 2, 4, 8 degrees, each with a 25% margin; a cap of
//      many pixels is read on a lattice of every s-th row and column, at most ~1000 samples, each
//      standing for s^2 pixels). Its radius theta_c is that of the
//      disc with the core's solid angle, plus the peak pixel's own radius sqrt(dw / pi) (an area,
//      so a few stray bright pixels do not count as a wide source); its centre the
//      luminance-weighted centroid;
//   3. the region: the cap of radius theta_c + glare around that centre, glare = the larger of
//      glareDeg, two pixels and theta_c / 2; it takes the glare around the source too (at
//      1024x512 a sun's glare holds 15-20% of its power; 3 degrees rather than 1 also take a hazy
//      sun's aureole, and lower every sunlit map's error in README's table);
//   4. the fill: per channel, the median of the ring [theta_r, theta_r + ring] around it (ringDeg,
//      at least three pixels): the sky that the source hides. A wide ring is read on a lattice
//      (~1000 pixels), and with it an estimate of the light's share drops a source below half of
//      minShare before its region is read whole;
//   5. the light: per pixel of the region, max(L - fill, 0). Its power is the sum of that times
//      dw (per channel, with the layout's exact solid angles); its direction the
//      luminance-power-weighted centroid; its angular radius that of the disc whose solid angle
//      is the pixels at or above half the largest excess luminance. What it takes from the
//      coefficients is the excess projected with the projector's own weights
//      (Projector::addPixels), so residual + light is exactly the whole map.
// Decision rule: a light is kept when
//   - theta_c <= maxRadiusDeg (compact: the core's area is that of a disc no wider), and
//   - its luminance power is at least minShare of the whole map's (minClippedShare for a clipped
//     core: its power is only a lower bound, of a source too bright for the frame).
// Otherwise there is no (further) light and the map is left exactly as it is: a map with no
// dominant compact source keeps its whole coefficients. Up to maxLights lights are taken, each
// from what the previous ones left.
#include <array>
#include <cstddef>
#include <memory>
#include <vector>

#include "liveprobe/sh/projector.h"
#include "liveprobe/sh/sh.h"

namespace lp {

/// The most lights one frame carries: extracted (LightOptions::maxLights), read from a coefficients
/// file, and drawn (the shaders' MAX_LIGHTS).
inline constexpr int kMaxLights = 8;

/// A small disc light at infinity, in the R&H world frame.
struct Light {
  glm::vec3 dir{0.0f, 0.0f, 1.0f};  ///< unit direction towards the light
  float angularRadius = 0.0f;       ///< radians (0: a directional light)
  /// Integral of the light's radiance over its solid angle, per channel: the irradiance it gives
  /// a surface facing it. The same units as the coefficients (radiance times steradians).
  Rgb power{0.0f};
  float share = 0.0f;    ///< its luminance power over the whole map's
  bool clipped = false;  ///< some of its pixels are at the 8-bit maximum: power is a lower bound
};

struct LightOptions {
  int maxLights = 1;              ///< the most lights taken out; 0 turns extraction off
  float minShare = 0.05f;         ///< smallest luminance power share of a light
  float minClippedShare = 0.01f;  ///< the same for a clipped core (a lower bound)
  float maxRadiusDeg = 8.0f;      ///< largest core radius of a light
  float coreFraction = 0.3f;  ///< core: pixels at or above this fraction of the peak's luminance
  float glareDeg = 3.0f;      ///< taken around the core with it
  float ringDeg = 1.5f;       ///< width of the ring whose median fills the source
  /// A stream's hysteresis: the directions (in the frame's own orientation) of the lights the
  /// frame before gave. A peak within heldDeg of one of them is a light down to heldFraction of
  /// the share it needs otherwise, so a source at the threshold does not come and go from frame
  /// to frame. Empty (one frame, or a stream's first): no hysteresis.
  std::vector<glm::vec3> held;
  float heldFraction = 0.5f;
  float heldDeg = 5.0f;
};

/// What a frame splits into: the sky's coefficients and the lights.
struct LightSplit {
  Sh9 residual;  ///< radiance coefficients of the map with the lights' pixels filled
  std::vector<Light> lights;
};

/// Irradiance of a uniform disc light at normal n, the exact clamped cosine (the spherical cap's
/// form factor, Snyder 1996, as in Lagarde & de Rousiers 2014, "Moving Frostbite to PBR", eq. 15):
/// power * (1 + cos a)/2 * cos b where the whole disc is above the surface's horizon, the
/// horizon-clipped integral where it straddles it (for a disc under 1.15 degrees, the flat-disc
/// form of that band, whose float terms do not cancel), 0 below. The same formula is the GLSL's
/// (shading/gl/src/shaders.cpp, lightIrradiance): keep the two identical.
glm::vec3 lightIrradiance(const Light& light, glm::vec3 n);

/// E(n) of coefficients and lights: evalIrradiance(residual, n) + sum of lightIrradiance.
glm::vec3 evalIrradiance(const Sh9& residual, const std::vector<Light>& lights, glm::vec3 n);

/// Finds the lights of frames of one projector's layout and size. Each light touches only the
/// pixels near it, read in runs along image rows: an equirect cap is one run of columns per row;
/// other layouts are indexed once, here, by direction (a 1-degree latitude-longitude grid of runs
/// of pixels). The cost is the peak search over the row peaks plus the source's neighbourhood.
class LightExtractor {
 public:
  explicit LightExtractor(const Projector& projector);
  ~LightExtractor();
  LightExtractor(LightExtractor&&) noexcept;
  LightExtractor& operator=(LightExtractor&&) noexcept;

  /// Splits `frame` (whose whole coefficients are `whole` and row peaks `rowPeaks`, both from
  /// Projector::project) into the residual coefficients and up to options.maxLights lights, in
  /// the frame's own orientation (turn both with rotateSplit). It runs on the calling thread:
  /// its passes are tens of microseconds, less than handing work to a pool costs.
  LightSplit extract(const PanoramaView& frame, const Sh9& whole,
                     const std::vector<float>& rowPeaks, const LightOptions& options) const;

 private:
  struct Index;
  struct Search;
  const Projector* projector_;
  std::unique_ptr<const Index> index_;
};

/// Radiance coefficients of the lights themselves: a uniform disc of power P, radius a, towards d
/// projects to P Y_lm(d) times 1, (1 + cos a)/2 and cos a (1 + cos a)/2 for bands 0, 1, 2. So
/// residual + lightsToSh(lights) is the whole map's coefficients (for what the lights took).
Sh9 lightsToSh(const std::vector<Light>& lights);

/// The split turned by `rotation` (world from file, as rotateSh): the residual by rotateSh, each
/// light's direction by the matrix.
LightSplit rotateSplit(const LightSplit& split, const glm::mat3& rotation);

/// One call: project, then extract (for tools and tests).
LightSplit projectWithLights(const PanoramaView& frame, const LightOptions& options,
                             Executor* executor = nullptr);

}  // namespace lp
