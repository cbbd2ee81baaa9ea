#pragma once
// The bracket merge's pixel loop (private to liveprobe::capture): one row of a window's frames
// merged into radiance, with the sums its confidence takes. One Highway source compiled for every
// SIMD path of liveprobe/sh/simd.h; the path in use is the projection's (LIVEPROBE_SIMD).
// hdr_merge.h says what a merge does; this is how one row of it runs.
#include <cstddef>
#include <cstdint>

namespace lp::merge {

/// The most frames a row merges (lp::kMaxBracket).
inline constexpr int kMaxFrames = 5;

struct RowInput {
  /// The frames the merge uses, oldest first and the newest last (frames left out whole are not
  /// here): this row's pixels (B, G, R bytes) and radianceScale (1 / exposure time) of each.
  int frames = 0;
  const std::uint8_t* bgr[kMaxFrames] = {};
  float scale[kMaxFrames] = {};
  int longest = 0;            ///< which of them has the longest exposure
  const float* lut[3] = {};   ///< the response: linear per code, for R, G and B
  int floor = 0, clip = 255;  ///< noise floor and clip level (codes)
  int wellExposed = 16;       ///< codes from here up are compared as ratios
  float wellLinear = 0,
        belowClipLinear = 0;  ///< green's linear at wellExposed, at surely-unclipped
  float inv2s2 = 0;           ///< 1 / (2 sigma^2) of the motion weighting
  int width = 0;
  /// Luminance per pixel: the last merge's (read only where `fresh`), this merge's (written; may
  /// be `previous` itself: each pixel is read before it is written), and the last trusted merge's.
  const float* previous = nullptr;
  float* luminance = nullptr;
  const float* reference = nullptr;
  bool fresh = false;
  /// Per pixel, where the older frames were turned to the newest (null: not turned): the least
  /// and the most the newest frame read over the pixel and its eight neighbours (the largest
  /// channel's code). A turned reading is a fraction of a pixel off: it is judged against the
  /// neighbourhood, not the pixel alone; and beside the newest's clipped pixels, an older,
  /// shorter exposure that reads brighter than the newest is the edge of the source the newest
  /// clips: the newest reading gives way.
  const std::uint8_t* nearLow = nullptr;
  const std::uint8_t* nearHigh = nullptr;
  float* rgb = nullptr;  ///< the merged radiance, R, G, B per pixel (null: not written)
  /// Equirect frames projected as they merge: the five column integrals of the row
  /// (EquirectIntegrals::col, zero-padded to a multiple of 16), or null: no projection.
  const float* col[5] = {};
};

/// A row's sums (unweighted by its solid angle).
struct RowSums {
  double power = 0, clippedPower = 0, clippedEstimate = 0, lostPower = 0;
  std::size_t dark = 0;
  float brightest = -1;  ///< the largest luminance; the flags are of its first pixel
  bool brightestClipped = false, brightestFresh = true;
  /// With RowInput::col: the merged radiance's column-weighted sums, [column integral][R, G, B].
  double col[5][3] = {};
};

using RowKernel = RowSums (*)(const RowInput& in);

/// The row merge of the path in use (lp::simd::current()).
RowKernel active();

}  // namespace lp::merge
