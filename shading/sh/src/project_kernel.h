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

/// Per pixel of a sample layout, from its direction d and solid angle dw: q = sqrt(dw) and
/// q d, as four streams (a pixel's index into each). The ten products the projection sums are
/// quadratic in them, so they need no per-pixel table of weights:
///   P0 q^2, P1 q y, P2 q z, P3 q x, P4 x y, P5 y z, P6 3 z^2 - q^2, P7 x z, P8 x^2 - y^2,
///   P9 max(x ux + y uy + z uz, 0) q
/// (x, y, z the streams, i.e. sqrt(dw) times the direction; u the ground's up): Y_lm dw is
/// P0..P8 times the basis constants of liveprobe/sh/sh.h, P9 the pixel's cosine to the up.
struct SampleStreams {
  const float* q;
  const float* x;
  const float* y;
  const float* z;
};
inline constexpr int kProducts = 10;

struct Kernels {
  /// acc += row factors of row i times the 15 column-weighted sums of `row` (3 * width floats;
  /// the sums keep the row's channel order). A non-null `peak` gets the row's largest value.
  void (*equirectRow)(const EquirectTables& t, const float* row, int i, LaneSums& acc, float* peak);
  /// out[3k + c] += sum over n pixels of rgb[3i + c] * P_k(i), for the ten products of
  /// SampleStreams (from each stream's first pixel on; every stream readable a whole vector past
  /// the n-th).
  void (*sampleSums)(const float* rgb, std::size_t n, SampleStreams s, const float* up,
                     double* out);
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
