#pragma once
// Aligning the frames of an exposure bracket to the newest: the camera's rotation between frames,
// estimated from the frames themselves, and older frames turned by it before they are merged.
//
// What is estimated: the camera's rotation rate (a rotation vector per camera frame, about any
// axis), taken as steady over the last two brackets; a scene that moves within itself is left
// to the merge's agreement test. How: each frame's log luminance in radiance units (its exposure
// divided out, so frames of different exposures compare where both measured) at up to 160
// pixels wide and two halvings; Lucas-Kanade on the sphere, coarse to fine, in the three
// parameters of a small rotation (the Jacobian of a pixel is d x grad I), Huber-weighted so that
// what moved within the scene pulls little, and without the two of 32 regions of the sphere that
// hold the most information (a rotation must show everywhere, not only where the sun moves).
// Each new frame is compared with the latest earlier frame of its own exposure (the most pixels
// measured in both) and with the frame before; the measured rates of the last two brackets are
// combined by their information, with a weak prior on no rotation (a frame that measured
// nothing, a short exposure of a dark scene, is carried by the others).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <glm/glm.hpp>
#include <vector>

#include "liveprobe/frame/frame.h"
#include "liveprobe/sh/executor.h"

namespace lp::align {

/// The smallest frame whose turn is estimated (and so the smallest turned): a smaller one is
/// merged as it comes.
inline constexpr int kLeastWidth = 32, kLeastHeight = 16;

/// One level of a frame's log-luminance pyramid: equirect, NaN where no reading is measured.
struct LogLevel {
  int width = 0, height = 0;
  std::vector<float> value;
};
inline constexpr int kLevels = 3;
using LogPyramid = std::array<LogLevel, kLevels>;  ///< finest first

using ResponseTable = std::array<std::array<float, 256>, 3>;

/// The log luminance (radiance units: Frame::radianceScale applied) of an 8-bit equirect frame,
/// block-averaged to at most 160 pixels wide, where the largest channel of every pixel of the
/// block read between `floor` and `clip` (exclusive); then halved twice.
LogPyramid logPyramid(const Frame& frame, const ResponseTable& response, int floor, int clip);

/// The rotation exp([w]x) (Rodrigues).
glm::mat3 rotationFromVector(const glm::vec3& w);

/// One comparison of two pyramids: the rotation Q with now(d) = old(Q d), as guess * exp(delta).
struct PairEstimate {
  glm::vec3 delta{0.0f};
  glm::mat3 information{0.0f};  ///< of delta (inverse covariance, radians); 0 when rejected
  double inliers = 0;           ///< fraction of the overlap within the noise, at the finest level
};
PairEstimate estimatePair(const LogPyramid& old, const LogPyramid& now, const glm::mat3& guess);

/// The camera's turn between frames, from the frames: a rate (a rotation vector per camera
/// frame) measured between frames of the same exposure over the last brackets.
class RotationTracker {
 public:
  /// Adds a frame of the stream, in order; `sequence` counts the frames the camera took.
  void add(LogPyramid pyramid, double radianceScale, std::uint64_t sequence);
  /// Where the newest frame sees direction d, the frame of `sequence` saw turnSince(sequence) d.
  glm::mat3 turnSince(std::uint64_t sequence) const;
  void clear() { history_.clear(), measurements_.clear(), ratePerFrame_ = glm::vec3(0.0f); }

 private:
  struct Entry {
    LogPyramid pyramid;
    double scale;
    std::uint64_t sequence;
  };
  struct Measurement {
    std::uint64_t sequence;
    glm::dvec3 rate;
    glm::dmat3 information;
  };
  std::deque<Entry> history_;
  std::deque<Measurement> measurements_;
  glm::vec3 ratePerFrame_{0.0f};
};

/// How far a rotation moves a pixel of an equirect frame `width` wide, at most, in pixels.
double displacementPixels(const glm::mat3& q, int width);

/// A camera's response both ways: linear per code (R, G, B), and the nearest code per linear
/// value, from a table indexed by the value's float exponent and top 8 mantissa bits (buckets
/// 0.4% wide over 24 octaves: finer than a code step at every code).
class Coder {
 public:
  explicit Coder(const ResponseTable& response);
  const ResponseTable& linear() const { return linear_; }
  /// The code of channel `c` (0 R, 1 G, 2 B) nearest to linear value v.
  std::uint8_t code(int c, float v) const {
    const std::uint32_t bits = std::bit_cast<std::uint32_t>(v * inverseTop_[std::size_t(c)]);
    const std::uint32_t i = std::clamp<std::uint32_t>(bits >> 15, kFirst, kLast) - kFirst;
    return table_[std::size_t(c)][i];
  }
  /// What code() reads, for a processor that codes back itself (merge::FrameInput::Recode).
  const std::uint8_t* table(int c) const { return table_[std::size_t(c)].data(); }
  float inverseTop(int c) const { return inverseTop_[std::size_t(c)]; }
  // Buckets from 2^-24 to 1 (of the curve's top), below and above clamped (negatives too: their
  // sign bit puts them above).
  static constexpr std::uint32_t kFirst = 103u << 8, kLast = 127u << 8;

 private:
  ResponseTable linear_;
  std::array<std::array<std::uint8_t, kLast - kFirst + 1>, 3> table_{};
  std::array<float, 3> inverseTop_{};
};

/// Where an equirect frame's pixels read from under a turn q (dst(d) = src(q d)): exact at nodes
/// every kTurnGrid pixels (the last row's at row h - 1), linear between them along the row and
/// down the column, and exact per pixel in the `polar` rows at each pole. Per node (nodesX
/// across, row by row), the column read from less the node's own (unwrapped across the seam), and
/// the row read from.
inline constexpr int kTurnGrid = 16;
struct TurnGrid {
  int nodesX = 0, nodesY = 0, polar = 0;
  std::vector<float> offset, row;
};
TurnGrid turnGrid(int width, int height, const glm::mat3& q);

/// dst(d) = src(q d) for an 8-bit BGR equirect frame: bilinear in linear units, coded back to
/// the nearest code; a pixel whose corners are clipped (a code at or above `clip`) by half their
/// weight or more reads as the clipped corner of most weight. `step` > 1: only every step-th
/// pixel of every step-th row, from step / 2 (a sparse grid; the rest of dst is left as it is).
/// `grid`: turnGrid(width, height, q) where the caller has it already.
void turnCodes(const std::uint8_t* src, int width, int height, const glm::mat3& q,
               const Coder& coder, int clip, std::uint8_t* dst, Executor* executor, int step = 1,
               const TurnGrid* grid = nullptr);
/// dst(d) = src(q d) for one float per pixel, the nearest pixel.
void turnLuminance(const float* src, int width, int height, const glm::mat3& q, float* dst,
                   Executor* executor);

/// For each pixel of an 8-bit BGR equirect frame, the least and the most of its largest channel's
/// code over the pixel and its eight neighbours (columns wrap).
void neighbourhood(const std::uint8_t* bgr, int width, int height, std::uint8_t* low,
                   std::uint8_t* high, Executor* executor);

}  // namespace lp::align
