#pragma once
// A chrome ball found in a camera's frame (--circle auto): OpenCV's gradient Hough transform for
// where it is, its rim's edge along rays out of the centre for a circle to a pixel or so, then
// the rim's own model fitted to a tenth of a pixel (what the orthographic ball's rim asks: a
// fifth of a pixel of radius moves its coefficients by about 0.4% of L00).
#include <optional>

#include "liveprobe/frame/frame.h"

namespace lp {

/// A circle in pixel coordinates (x right, y down, pixel centres at +0.5, as layoutPixel), and
/// how well the rim's model fitted it.
struct BallCircle {
  double x = 0, y = 0, radius = 0;
  double rimResidual = 0;  ///< RMS distance of the sectors' rim edges from the circle, pixels
  int rimSectors = 0;      ///< sectors (of 32) whose edge the circle kept
};

/// The ball in `frame` (8-bit or float): the circle of a radius from a tenth to a half of the
/// frame's shorter side whose rim holds (the rim's edges within 0.5 px RMS of it), or none.
std::optional<BallCircle> findBall(const Frame& frame);

}  // namespace lp
