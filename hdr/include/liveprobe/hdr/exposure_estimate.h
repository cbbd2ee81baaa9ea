#pragma once
// Which exposure time each frame of a bracket was taken with, from its pixels, for a camera that
// does not say (most webcams: no UVC metadata). Comparametric (Mann and Picard; Grossberg and
// Nayar): two frames of one scene at exposures t1 and t2 read response^-1(code) = L t / t_clip at
// each pixel both measured well, so the median of log(linear2 / linear1) over those pixels is
// log(t2 / t1), whatever the scene, robust to the few pixels that moved. A camera takes a new
// exposure some frames after it is asked and may round it; neither is assumed: each frame is
// measured against the frames before it whose exposure is known, and named after the exposure
// asked (or the one in force before the bracket) that its estimate agrees with.
// Stops far apart share few well-measured pixels (a -12 EV frame of a sunlit sky reads only the
// sun, which clips at -6 EV): such a frame is named after the exposure the known frames
// contradict least, each pixel read as an interval (a clipped code a lower bound, a dark one an
// upper bound), when one exposure explains it and the others do not; it is then taken at the
// exposure asked. A frame whose exposure the known frames contradict on more than 5% of it, or
// that agrees with no exposure (taken while the sensor changed), is left out, and counted.
#include <cstddef>
#include <deque>
#include <optional>
#include <vector>

#include "liveprobe/frame/frame.h"
#include "liveprobe/hdr/merge.h"

namespace lp {

class ExposureIdentifier {
 public:
  /// `asked`: the bracket's exposure times (seconds) as the control was set; `response`: the
  /// camera's.
  ExposureIdentifier(std::vector<double> asked, CameraResponse response);

  /// The anchor: a frame taken at `base` seconds, the exposure in force before the bracket (the
  /// locked one, as the camera reports it or as it was written), itself a candidate; what was
  /// known before is forgotten. Throws lp::Error unless `base` is positive.
  void seed(const Frame& frame, double base);
  /// The exposure time (seconds) `frame` (8-bit) was taken with, or nullopt when its estimate
  /// agrees with no exposure asked. A frame at the base exposure is given the base exactly (the
  /// anchor); the others their estimate, which a camera's rounding moves off what was asked.
  std::optional<double> identify(const Frame& frame);
  /// The last frame's estimate before it was named (seconds; 0 when it could not be measured).
  double lastEstimate() const { return lastEstimate_; }

  // A camera that follows a known schedule (Bracketing: each frame's exposure is the one asked
  // some frames before it): the pixels confirm the schedule, they do not name the exposure.
  /// The exposure `frame` (8-bit) was taken with, from its ratio to the known frame that shares
  /// the most well-measured samples with it, whatever was asked; nullopt where too few samples
  /// are shared (a dark or white frame, a stop far from every known one). Holds the frame for
  /// contradiction() and confirm(); remembers nothing.
  std::optional<double> measure(const Frame& frame);
  /// The share of the measured frame's samples the known frames contradict, were it taken at
  /// `seconds` (0 when nothing is known to compare with).
  double contradiction(double seconds) const;
  /// The measured frame is known to be taken at `seconds`, for the frames after it; `alone`:
  /// the frames known before are forgotten (the scene changed past comparing with them).
  void confirm(double seconds, bool alone = false);

 private:
  struct Known {
    std::vector<float> linear;  ///< green, response^-1, per sample; 0 where not well measured
    std::vector<float> lo, hi;  ///< what each sample's code allows of response^-1
    double seconds = 0;
  };
  Known sample(const Frame& frame) const;
  void remember(const Frame& frame, double seconds);  ///< known, for the frames after it
  std::optional<double> byRatio(Known& now);
  /// The estimate from the ratio to the known frames (seconds), or nullopt.
  std::optional<double> ratioEstimate(const Known& now) const;
  std::optional<double> byContradiction(const Known& now) const;
  /// Per exposure in `times`: the share of samples the known frames contradict were this frame
  /// taken at it (empty when nothing is known to compare with).
  std::vector<double> contradicted(const Known& now, const std::vector<double>& times) const;
  std::vector<double> asked_, candidates_;  ///< candidates: asked and base, seconds
  double base_ = 0, tolerance_ = 0.3;       ///< tolerance: in stops
  CameraResponse response_;
  std::deque<Known> known_;  ///< newest last
  double lastEstimate_ = 0;
  std::optional<Known> measured_;  ///< the last measure()'s frame
};

}  // namespace lp
