#pragma once
// The standard method, kept for comparison with the nine-coefficient representation:
// brute-force hemispherical integration E(n) = sum_i L_i max(n . w_i, 0) dw_i for every output
// normal. O(T S) for T normals and S pixels. Same conventions as liveprobe/sh/sh.h.
#include <cstddef>
#include <functional>
#include <vector>

#include "liveprobe/sh/executor.h"
#include "liveprobe/sh/sh.h"

namespace lp {

/// Called on the calling thread with the number of normals started; returning false stops the
/// integration early (the remaining normals are left zero).
using BruteProgress = std::function<bool(std::size_t done)>;

/// Irradiance at each of `normals` (unit, R&H frame) from an image given as samples (see
/// projectSamples for rgb/pixelStride). Runs on the executor's threads (nullptr: the caller's).
/// Inner sums are float over blocks, totals in double.
std::vector<Rgb> bruteIrradiance(const float* rgb, std::size_t pixelStride,
                                 const SphereSample* samples, std::size_t count,
                                 const std::vector<glm::vec3>& normals,
                                 Executor* executor = nullptr, const BruteProgress& progress = {});

}  // namespace lp
