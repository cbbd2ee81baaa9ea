#pragma once
// High dynamic range from an 8-bit camera: the last N frames, each taken with its own exposure
// time, merged into one radiance frame (Debevec and Malik, SIGGRAPH 1997). Per pixel, a weighted
// average of response^-1(code) / exposure over the frames where the pixel is neither clipped nor
// in the noise floor, weighted by the hat (mid-range codes count most) times the exposure time (a
// longer exposure gathers more light for the same code noise); a pixel no frame measured but some
// frame clipped keeps the highest bound a clipped reading sets (the shortest clipped exposure's
// value), a lower bound, and is counted as clipped.
//
// Motion between the frames of a set (the newest frame is the truth of now): where an older
// reading and the newest contradict each other (radiances 25% apart where both are well exposed,
// or one dark or clipped where the other's reading says it cannot be), the older one is dropped,
// and what it saw counts as lost light, as does what the last merge saw where the newest frame
// rules it out; where both agree, the older one is weighed by how closely
// (exp(-d^2 / (2 sigma^2)), d the log ratio). A frame that contradicts the newest on most of the
// picture (a hand over the lens, a flash) is left out whole. A source the newest frame clips (the
// sun at 0 EV) can only come from an older, shorter exposure: it lags by up to N - 1 frames.
// Where the camera turns between the frames (a rig, a vehicle, a hand), the older frames of an
// equirect set are first turned to the newest by the rotation the frames show (bracket_align.h):
// the sun read N - 1 frames ago is merged where the newest frame sees it. A turned reading is a
// fraction of a pixel off: it contradicts the newest only where it fits none of the newest's
// readings over the pixel and its eight neighbours; where a shorter exposure reads brighter than
// a longer one's well-exposed reading, the longer gives way (it misses light the shorter measured
// beside its clipped core), the newest frame too where it clips the pixel or one beside it.
//
// Each merge also says how far it can be trusted (FrameConfidence).
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "liveprobe/frame/frame.h"
#include "liveprobe/frame/frame_confidence.h"
#include "liveprobe/hdr/merge_frame.h"
#include "liveprobe/hdr/response.h"
#include "liveprobe/sh/executor.h"
#include "liveprobe/sh/projector.h"
#include "liveprobe/sh/sh.h"

namespace lp {

struct BracketView;
struct MergeTally;

/// The most frames one merge takes.
inline constexpr int kMaxBracket = merge::kMaxFrames;

struct MergeOptions {
  int frames = 3;  ///< the window: each merge uses the last `frames` frames (1 to kMaxBracket)
  CameraResponse response = CameraResponse::srgb();
  int noiseFloor = 6;   ///< a pixel whose largest channel is at or below this is noise
  int clipLevel = 250;  ///< a pixel with a channel at or above this is clipped
  /// Solid-angle weights for clippedShare: rows of an equirect frame weigh sin(theta).
  bool equirect = true;
  double ghostSigma = 0.3;  ///< motion weighting: sigma of the log radiance ratio
  /// Equirect frames: older frames turned to the newest by the camera's rotation between them,
  /// estimated from the frames.
  bool align = true;
};

/// A merge that projects as it goes (equirect frames): each row's radiance weighed by the
/// projector's pixel integrals while the row is in cache, so the coefficients cost no second
/// pass over a float frame, and the frame is written only where something reads it (a display,
/// the light search).
struct MergeProjection {
  /// The projector's integrals for the frame's size (Projector::equirectIntegrals()).
  const EquirectIntegrals* integrals = nullptr;
  /// false: `out` gets the merged frame's size, times and scale, and no pixels.
  bool keepFrame = true;
  /// With a frame kernel (BracketMerger::setFrameKernel): the kernel keeps the merged frame where
  /// it merges (merge::FrameInput::rgbKept), for a display drawing there; with keepFrame too,
  /// `out` gets a copy (a light search reads it).
  bool keepWhereMerged = false;
  /// The result: the merged frame's radiance coefficients, the sums Projector::project makes of
  /// it (in its units, before any photometry or rotation), and its row peaks as that makes them
  /// (each row's largest channel value: where a light search starts).
  Sh9 coefficients;
  std::vector<float> rowPeaks;
};

class BracketMerger {
 public:
  explicit BracketMerger(MergeOptions options);
  ~BracketMerger();
  BracketMerger(BracketMerger&&) noexcept;
  BracketMerger& operator=(BracketMerger&&) noexcept;

  /// Adds an 8-bit frame, whose Frame::radianceScale is 1 / its exposure time (what the camera
  /// reported for it), and merges the window into `out`: RgbF32 radiance in the same units,
  /// radianceScale 1, the newest frame's sequence and timestamp, and the oldest frame's capture
  /// time (the latency of the merge starts there). Throws lp::Error on a float frame. A frame of
  /// another size starts the window afresh.
  FrameConfidence add(const Frame& in, Frame& out, Executor* executor = nullptr);
  /// The same, projecting as it merges. Throws lp::Error where the integrals are not of the
  /// frame's size.
  FrameConfidence add(const Frame& in, Frame& out, Executor* executor, MergeProjection& projection);

  /// The pixel loop run elsewhere from here on (the GPU's: liveprobe/gl/gpu_merge.h), in place
  /// of the CPU's row kernel; none: the CPU's again. `turns`: it turns the older frames itself
  /// (merge::FrameInput::turn); else they come to it turned. `fetch`: it keeps each merge's
  /// luminance, read back only where the merger needs it (the camera turned); none: it writes
  /// the luminance back every merge. Everything else stays the merger's.
  void setFrameKernel(merge::FrameKernel kernel, bool turns = false,
                      merge::LuminanceFetch fetch = {});
  bool hasFrameKernel() const { return bool(frameKernel_); }

  const MergeOptions& options() const { return opt_; }
  std::size_t held() const { return window_.size(); }

 private:
  void push(const Frame& in);
  /// The window's pixels as the merge reads them: older frames turned to the newest.
  std::array<const std::uint8_t*, kMaxBracket> alignedWindow(Executor* executor);
  /// The window as the pixel loop reads it; `exposures`: the distinct exposure times in use.
  BracketView prepare(const std::array<const std::uint8_t*, kMaxBracket>& pixels,
                      int& exposures) const;
  /// The frames of the window that do not contradict the newest as a whole.
  std::array<bool, kMaxBracket> usableFrames(const BracketView& view) const;
  /// The frame's luminance: the last merge's, this merge's (possibly the same buffer), and the
  /// last trusted merge's.
  struct Luminance {
    const float* previous;
    float* out;
    const float* reference;
  };
  /// The merge's frames and buffers as a pixel loop reads them; `rgb`: the merged frame (or
  /// null).
  merge::FrameInput frameInput(const BracketView& view, float* rgb, const Luminance& lum,
                               bool fresh, const EquirectIntegrals* project) const;
  /// previous_ and/or reference_ read back from the frame kernel where it kept them.
  void bringBack(bool previous, bool reference);
  /// A key no frame or luminance of the process had (merge::FrameInput::key).
  static std::uint64_t newKey();
  /// A row's sums weighed by its solid angle, and its coefficients' sums where it projects.
  MergeTally tally(const merge::RowSums& sums, std::size_t y,
                   const EquirectIntegrals* project) const;
  MergeOptions opt_;
  std::deque<Frame> window_;          ///< oldest first
  std::vector<float> previous_;       ///< the last merge's luminance, per pixel
  std::vector<float> reference_;      ///< the last trusted merge's (complete, in agreement)
  bool referenceIsPrevious_ = false;  ///< the last merge was trusted: reference_ is stale
  /// previous_ and reference_ not yet read back from the frame kernel, which keeps them by key
  /// (setFrameKernel's `fetch`).
  bool previousAway_ = false, referenceAway_ = false;
  std::deque<double> agreements_;   ///< per window frame: the agreement of its own merge
  std::deque<std::uint64_t> keys_;  ///< per window frame: merge::FrameInput::key
  /// previous_'s and reference_'s keys (merge::FrameInput::previousKey): what they hold.
  std::uint64_t previousKey_ = 0, referenceKey_ = 0;
  struct Alignment;                   ///< the camera's rotation, and the frames turned by it
  std::unique_ptr<Alignment> align_;  ///< null where the frames are not aligned
  merge::FrameKernel frameKernel_;    ///< setFrameKernel()
  bool kernelTurns_ = false;
  merge::LuminanceFetch fetchLuminance_;
};

}  // namespace lp
