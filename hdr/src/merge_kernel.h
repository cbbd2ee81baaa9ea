#pragma once
// The bracket merge's pixel loop (private to liveprobe::hdr): one row of a window's frames
// merged into radiance, with the sums its confidence takes. One Highway source compiled for every
// SIMD path of liveprobe/sh/simd.h; the path in use is the projection's (LIVEPROBE_SIMD).
// merge.h says what a merge does; this is how one row of it runs; merge_frame.h is the whole
// frame's loop as another processor takes it.
#include <cstddef>
#include <cstdint>

#include "liveprobe/hdr/merge_frame.h"

namespace lp::merge {

/// One row: a FrameInput's pointers advanced to the row (each frame's bytes, the luminance rows,
/// the neighbourhood rows, the merged row), the column integrals as they are (zero-padded to a
/// multiple of 16).
struct RowInput : FrameInput {
  /// The row `y` of `frame`.
  static RowInput of(const FrameInput& frame, std::size_t y);
};

using RowKernel = RowSums (*)(const RowInput& in);

/// The row merge of the path in use (lp::simd::current()).
RowKernel active();

}  // namespace lp::merge
