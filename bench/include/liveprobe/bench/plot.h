#pragma once
// The frame-time plot, by gnuplot (pngcairo): each frame's stages stacked and filled against the
// frame number, the warm-up frames of each run shaded, and beside it a histogram of the frame
// totals with the median and p95 marked.
#include <string>

#include "liveprobe/bench/runs.h"

namespace lp::bench {

/// Frames at the start of each run shaded as warm-up (caches, llvmpipe's shader compiles).
inline constexpr int kWarmupFrames = 3;

/// Writes the plot to `path` (.png) under a temporary name and renames it; gnuplot's inputs are
/// removed. Throws lp::Error naming `path` where gnuplot is missing (and which package has it) or
/// fails (with its first line).
void drawStagePlot(const std::string& path, const Runs& runs, const std::string& title);

}  // namespace lp::bench
