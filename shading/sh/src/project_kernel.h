#pragma once
// The projection kernels (private to liveprobe::sh). One Highway source compiled for every SIMD
// path of liveprobe/sh/simd.h; active() is the path in use. Sums run in float over at most one
// row (or 1024 pixels) and in double beyond, so a 4K frame stays within ~1e-7 of L00 of a
// float64 sum.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "liveprobe/sh/projector.h"

namespace lp::kernel {

/// The widest vector of any path, in floats (AVX-512).
inline constexpr int kMaxLanes = 16;

/// The equirect tables (liveprobe/sh/projector.h has them, for the GPU projection too).
using EquirectTables = EquirectIntegrals;

/// Float lanes of the 27 sums (coefficient-major, then the frame's channels), kMaxLanes each; a
/// path uses as many lanes as its vectors have and leaves the rest zero.
struct alignas(64) LaneSums {
  float v[27 * kMaxLanes];
};

struct Kernels {
  /// acc += row factors of row i times the 15 column-weighted sums of `row` (3 * width floats;
  /// the sums keep the row's channel order). A non-null `peak` gets the row's largest value.
  void (*equirectRow)(const EquirectTables& t, const float* row, int i, LaneSums& acc, float* peak);
  /// out[3k + c] += sum over n pixels of rgb[3i + c] * w_k[i]. `blocked` holds the weights in
  /// blocks of 16 pixels: w_k of pixel 16 b + l at blocked[(9 b + k) * 16 + l], zero-padded to a
  /// whole block (one sequential stream, which the prefetchers follow).
  void (*weightedSums)(const float* rgb, std::size_t n, const float* blocked, double* out);
  /// dst[i] = lut[src[i]] (a 256-entry table).
  void (*decodeU8)(const std::uint8_t* src, const float* lut, float* dst, std::size_t n);
  /// IEEE binary16 to float.
  void (*decodeF16)(const std::uint16_t* src, float* dst, std::size_t n);
  /// The largest of n floats (-inf for none).
  float (*maxOf)(const float* p, std::size_t n);
};

/// The kernels of the path in use (liveprobe/sh/simd.h).
const Kernels& active();

}  // namespace lp::kernel
