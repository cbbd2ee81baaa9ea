#pragma once
// The bracket merge's pixel loop over a whole frame, as another processor runs it (the GPU:
// liveprobe/gl/gpu_merge.h): what lp::BracketMerger hands it, and each row's sums it hands back.
// The merger keeps everything else (the window, the alignment, the frames left out whole, the
// confidence); merge.h says what a merge does, and the CPU's row kernel (merge_kernel.cpp) is
// the reference every other runs against.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace lp::merge {

/// The most frames a merge takes (lp::kMaxBracket).
inline constexpr int kMaxFrames = 5;

/// One merge's frames and buffers, whole frames of width x height pixels, rows top to bottom.
struct FrameInput {
  /// The frames the merge uses, oldest first and the newest last (frames left out whole are not
  /// here): their pixels (B, G, R bytes, older frames already turned to the newest) and
  /// radianceScale (1 / exposure time) of each.
  int frames = 0;
  const std::uint8_t* bgr[kMaxFrames] = {};
  float scale[kMaxFrames] = {};
  /// Each frame's identity while its pixels stay as they are (a number given as it joins a window,
  /// never given again in the process), or 0 where they change from one merge to the next (turned
  /// to the newest): what a processor uploaded under an identity it may keep and reuse.
  std::uint64_t key[kMaxFrames] = {};
  /// Where the processor turns the older frames itself (BracketMerger::setFrameKernel's
  /// `turns`): each frame's turn to the newest, dst(d) = src(q d) for an equirect frame (q
  /// column-major), applied to the frame as it was taken (`bgr`, `key`), bilinear in linear units
  /// and coded back through `recode`, as the CPU turns it (a pixel whose corners are clipped by
  /// half their weight or more reads as the clipped corner of most weight).
  struct Turn {
    bool apply = false;
    float q[9] = {};
    /// Where each pixel reads from, as the CPU finds it: exact at nodes every 16 pixels (the
    /// last row's at row height - 1), linear between them along the row and down the column,
    /// exact per pixel (from q) in the `polar` rows at each pole. Per node (nodesX across, row by
    /// row): the column read from less the node's own, and the row read from.
    int nodesX = 0, nodesY = 0, polar = 0;
    const float* offset = nullptr;
    const float* row = nullptr;
  };
  Turn turn[kMaxFrames];
  /// The response's way back to a code, per channel (R, G, B): the code of linear v is
  /// table[c][min(max(bits(v * inverseTop[c]) >> 15, first), last) - first].
  struct Recode {
    const std::uint8_t* table[3] = {};
    float inverseTop[3] = {};
    std::uint32_t first = 0, last = 0;
  } recode;
  int longest = 0;            ///< which of them has the longest exposure
  const float* lut[3] = {};   ///< the response: linear per code (256 each), for R, G and B
  int floor = 0, clip = 255;  ///< noise floor and clip level (codes)
  int wellExposed = 16;       ///< codes from here up are compared as ratios
  float wellLinear = 0,
        belowClipLinear = 0;  ///< green's linear at wellExposed, at surely-unclipped
  float inv2s2 = 0;           ///< 1 / (2 sigma^2) of the motion weighting
  int width = 0, height = 0;
  /// Luminance per pixel: the last merge's (read only where `fresh`), this merge's (written; may
  /// be `previous` itself: each pixel is read before it is written), and the last trusted merge's.
  const float* previous = nullptr;
  float* luminance = nullptr;
  const float* reference = nullptr;
  bool fresh = false;
  /// The luminance buffers' identities as in the keys of the frames: `previous` and `reference`
  /// as some earlier merge wrote them (0: turned since, or otherwise new), and this merge's.
  std::uint64_t previousKey = 0, referenceKey = 0, luminanceKey = 0;
  /// false: the processor keeps this merge's luminance (under luminanceKey) and need not write
  /// `luminance`; the merger reads it back where it needs it (LuminanceFetch).
  bool luminanceBack = true;
  /// Where the older frames were turned to the newest (null: not turned): the least and the most
  /// code the newest frame read over each pixel and its eight neighbours (its largest channel).
  const std::uint8_t* nearLow = nullptr;
  const std::uint8_t* nearHigh = nullptr;
  float* rgb = nullptr;  ///< the merged radiance, R, G, B per pixel (null: not written)
  /// The processor keeps the merged radiance where it runs (a GPU's buffer the display draws
  /// from: gl::GpuMerge::takeKeptImage); `rgb`, where given too, gets a copy of it.
  bool rgbKept = false;
  /// Equirect frames projected as they merge: the five column integrals (width floats each,
  /// EquirectIntegrals::col), or null: no projection.
  const float* col[5] = {};
};

/// A row's sums (unweighted by its solid angle).
struct RowSums {
  double power = 0, clippedPower = 0, clippedEstimate = 0, lostPower = 0;
  std::size_t dark = 0;
  float brightest = -1;  ///< the largest luminance; the flags are of its first pixel
  bool brightestClipped = false, brightestFresh = true;
  /// With FrameInput::col: the merged radiance's column-weighted sums, [column integral][R, G, B],
  /// and its largest channel value (Projector::project's row peak).
  double col[5][3] = {};
  float peak = 0;
};

/// A whole frame's pixel loop: writes `in`'s luminance (and rgb where asked) and `rows`
/// (height of them). Throws lp::Error (or one derived from it) where it cannot run.
using FrameKernel = std::function<void(const FrameInput& in, std::vector<RowSums>& rows)>;

/// Reads the luminance a FrameKernel kept under `key` (FrameInput::luminanceKey; width x height
/// floats) into `into`; false where it no longer holds it.
using LuminanceFetch = std::function<bool(std::uint64_t key, float* into)>;

}  // namespace lp::merge
