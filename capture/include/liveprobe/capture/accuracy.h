#pragma once
// SH irradiance against the brute-force hemispherical integral, with the paper's error measure.
#include <string>
#include <vector>

#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/sh/brute.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/sh.h"

namespace lp {

struct CompareResult {
  int width = 0, height = 0;       ///< the equirect grid of normals
  std::vector<float> ySh, yBrute;  ///< luminance of E at each normal, row-major
  double totalIntensity = 0;       ///< integral of Y(L) over the sphere
  double meanIrradiance = 0;       ///< solid-angle-weighted mean of Y(E_brute) (= total / 4)
  double meanFracTotal = 0, maxFracTotal = 0;  ///< |E_sh - E| / total intensity
  double meanRelMean = 0, maxRelMean = 0;      ///< |E_sh - E| / mean irradiance
  double minShOverMean = 0;                    ///< min Y(E_sh) / mean irradiance
  double shMs = 0, bruteMs = 0;
  Sh9 radiance;  ///< the map's coefficients (lights included), unwindowed, in the world frame
  /// With lights taken out: SH of the residual plus the lights, its errors, and the lights.
  bool sun = false;
  std::vector<float> ySun;
  double meanFracTotalSun = 0, maxFracTotalSun = 0;
  std::vector<Light> lights;
};

/// Evaluates both methods on a W x H equirect grid of normals (pixel centres, weighted by their
/// solid angle). `window` is applied to the SH coefficients first.
/// `orientation` turns the environment (world from file) for both methods. With `sun`, the
/// lights are also extracted (liveprobe/sh/lights.h) and SH-of-the-rest plus lights is measured
/// beside SH alone.
CompareResult compareIrradiance(const Image& img, const LayoutSpec& layout, int width, int height,
                                const BandWindow& window = {}, unsigned threads = 0,
                                const glm::mat3& orientation = glm::mat3(1.0f),
                                const BruteProgress& progress = {},
                                const LightOptions* sun = nullptr);

/// The same with the map already taken through the frame path: `lighting` from lp::FrameProcessor
/// (the same layout and orientation; its lights, where it has any, measured as `sun` above) and
/// `projectMs`, the time that took (tables made beforehand), which shMs includes. The map is
/// projected once: here only the brute force and the evaluations run.
CompareResult compareIrradiance(const Image& img, const LayoutSpec& layout,
                                const FrameLighting& lighting, double projectMs, bool sun,
                                int width, int height, const BandWindow& window = {},
                                unsigned threads = 0,
                                const glm::mat3& orientation = glm::mat3(1.0f),
                                const BruteProgress& progress = {});

/// The SH map (with lights taken out: SH of the rest plus the lights), the brute-force map (same
/// exposure) and |error| / total intensity with a colour scale, side by side, as an 8-bit PNG.
void saveCompareFigure(const std::string& path, const CompareResult& r);

}  // namespace lp
