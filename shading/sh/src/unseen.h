#pragma once
// What fills the directions a frame does not see, folded into the projection's per-pixel
// weights: every rule of liveprobe/sh/layout.h's UnseenRule is linear in the frame's pixels, so
// the fill costs nothing per frame.
#include <vector>

#include "liveprobe/sh/layout.h"

namespace lp::unseen {

/// Below this short of the whole sphere, samples cover it (their float solid angles' rounding).
inline constexpr double kWhole = 1e-5;

/// The share of the sphere that `samples` measure: their solid angles' sum over 4 pi, exactly 1
/// within kWhole of it.
double coverage(const std::vector<SphereSample>& samples);

/// Adds to `weights` (nine per pixel in blocks of 16, as Projector::blockedWeights) the weights
/// that give the coefficients of spec.unseen's fill of what the W x H frame does not see:
///   ground: each unseen direction below the horizon has L = albedo E_up / pi, with E_up the
///     exact cosine-weighted sum of what is seen above the horizon (and of its fill); each unseen
///     direction above the horizon takes the radiance of the nearest seen pixel on the edge;
///   mean: every unseen direction takes the solid-angle-weighted mean of the edge's pixels;
///   black: nothing.
/// The unseen directions are found on a grid of the sphere (256 x 128 cells, 8 x 8 where a
/// cell straddles the edge), each asked of layoutPixel.
void addFill(const LayoutSpec& spec, int width, int height,
             const std::vector<SphereSample>& samples, std::vector<float>& weights);

}  // namespace lp::unseen
