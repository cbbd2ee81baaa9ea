#pragma once
// How far a frame's lighting can be trusted: what the frame path carries of a merge (an 8-bit
// exposure bracket merged to radiance, liveprobe/hdr/merge.h) or of a single frame.
#include <algorithm>

namespace lp {

/// How far a frame's lighting can be trusted.
struct FrameConfidence {
  /// Fraction of the map's power in pixels clipped in every exposure, each at the most of its
  /// lower bound and what the last trusted merge measured there (a bracket missing its shortest
  /// reading loses the sun it held): still a lower bound, since their true radiance is unknown
  /// (weighted by solid angle for equirect frames, by pixel otherwise).
  double clippedShare = 0;
  /// Fraction of pixels no exposure read at a well-exposed code (16 and up): in the noise floor,
  /// or measured only in the few lowest codes (a covered lens, a bracket missing its longest).
  double darkShare = 0;
  /// The brightest pixel was measured unclipped in at least one exposure.
  bool brightestMeasured = true;
  /// 1 minus the power that older frames of the bracket (or the last merge) saw and the newest
  /// contradicts (radiances more than 25% apart, or dark or clipped where the other predicts
  /// otherwise: motion, flicker, a hand over the lens), relative to the power the merge keeps;
  /// 0 when as much is contradicted as is kept. 1 for a single frame. Where the brightest pixel
  /// is read by older frames only (the newest clips it), at most the agreement each merged frame
  /// of the window had when it was the newest: a scene that was moving then may have moved the
  /// light since.
  double agreement = 1;
  int exposures = 1;  ///< distinct exposure times merged (over a quarter stop apart)
  /// Every frame of a full window merged, each at its own exposure: none missing (start-up) or
  /// left out whole (a hand over the lens, a flash). A hold ends only on a complete merge.
  bool complete = true;

  /// The share of the sphere the frame measures (a lens sees part of it; the rest is the
  /// layout's unseen fill, liveprobe/sh/layout.h). 1 for the panoramic layouts.
  double coverage = 1;

  /// How well what was measured was measured, in [0, 1]: (1 - clippedShare) (1 - darkShare)
  /// agreement, and at most kUnmeasuredBrightest where the brightest pixel clipped in every
  /// exposure: then its power (the sun's share) is a lower bound at an unknown distance from the
  /// truth, and the clipped share says how much is known to be missing, not how much is.
  double measured() const {
    const double v = (1.0 - clippedShare) * (1.0 - darkShare) * agreement;
    return brightestMeasured ? v : std::min(v, kUnmeasuredBrightest);
  }
  /// One number in [0, 1]: measured() times coverage, since the unseen share is filled, not
  /// measured.
  double value() const { return measured() * coverage; }
  static constexpr double kUnmeasuredBrightest = 0.5;
};

}  // namespace lp
