#pragma once
// What fills the directions a frame does not see, folded into the projection's per-pixel
// weights: every rule of liveprobe/sh/layout.h's UnseenRule is linear in the frame's pixels, so
// the fill costs nothing per frame.
#include <array>
#include <cstddef>
#include <vector>

#include "liveprobe/sh/layout.h"

namespace lp::unseen {

/// Below this short of the whole sphere, samples cover it (their float solid angles' rounding).
inline constexpr double kWhole = 1e-5;

/// The share of the sphere that `samples` measure: their solid angles' sum over 4 pi, exactly 1
/// within kWhole of it.
double coverage(const std::vector<SphereSample>& samples);

/// The weights a rule's fill adds to the measured pixels' own Y_lm(dir) dw: all of them linear
/// in the pixels, and of two kinds.
///   - the ground (spec.unseen Ground): L = albedo E_up / pi on each unseen direction below the
///     horizon, E_up the exact cosine-weighted sum of the seen pixels (and of the sky's fill);
///     so every pixel p gets max(dir_p . up, 0) dw_p times `ground` (the ground's basis
///     integral times albedo / pi);
///   - the edge: each unseen direction above the horizon (Ground) takes the radiance of the
///     nearest seen pixel on the edge, every unseen direction (Mean) the solid-angle-weighted
///     mean of the edge's pixels: nine extra weights for each of `pixels` (row-major order),
///     the Ground ones with their share of the ground too.
/// Black fills nothing.
struct Fill {
  std::vector<std::size_t> pixels;
  std::vector<std::array<float, kShCount>> weights;  ///< per entry of `pixels`
  bool hasGround = false;
  std::array<float, kShCount> ground{};
  glm::vec3 up{0, 0, 1};  ///< unit

  /// The extra weights of pixel p (sample s): what it adds to Y_lm(dir) dw.
  std::array<float, kShCount> at(std::size_t p, const SphereSample& s) const;
};

/// The fill of what the W x H frame does not see. The unseen directions are found on a grid of
/// the sphere (256 x 128 cells, 8 x 8 where a cell straddles the edge), each asked of
/// layoutPixel.
Fill fill(const LayoutSpec& spec, int width, int height, const std::vector<SphereSample>& samples);

}  // namespace lp::unseen
