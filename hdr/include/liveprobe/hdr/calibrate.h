#pragma once
// A camera's response recovered from frames of one still scene at several exposure times.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "liveprobe/frame/exposure_control.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/hdr/response.h"

namespace lp {

/// The darkest code an 8-bit frame reads over a part of its scene (0.05% of its samples or more,
/// any channel): a calibration sweep goes shorter until this is kDarkestCode.
int darkestCode(const Frame& frame);

/// A camera's response recovered from 8-bit frames of one static scene, each with its own
/// exposure time (Frame::radianceScale = 1 / exposure): the least squares of the codes each pixel
/// took in each pair of frames (comparametric equations), with a smoothness over log(code) that
/// any power law passes freely; normalised so that green's power law over codes 32-240 reaches 1
/// at code 255; readFrom..readTo the codes every channel read. Throws lp::Error with fewer than 3
/// distinct exposures, with too few codes read, or when the recovered curve falls somewhere (too
/// few tones in the scene, or a scene that moved).
///
/// A camera that sends a colour shared by a block of pixels (YUYV: 2x1, NV12 and most MJPEG:
/// 2x2) gives a pixel's code in each channel only where its block reads one colour: only those
/// pixels are read, and not within 3 codes of 0 or 255 (where the YUV steps make a clipped
/// channel read as unclipped). The YUV's own 8-bit steps remain: such a curve holds within 3%
/// from kYuvTrustedFrom up (HdrMerge.TheResponseRecoveryAgainstOpenCvs).
struct ChromaBlock {
  int width = 1, height = 1;
};
inline constexpr int kYuvTrustedFrom = 16;
CameraResponse calibrateResponse(const std::vector<Frame>& frames, ChromaBlock chroma = {});

struct SweepOptions {
  int lowest = -6, highest = 3;  ///< whole stops from the locked exposure
  std::int32_t locked = 0;       ///< the locked exposure, 100 us
  int settle = 8;                ///< frames let pass after each change, at most
  std::string name;              ///< the camera, as errors name it
  /// Polled before each stop: true ends the sweep (a signal), with what it has.
  std::function<bool()> stopRequested;
  /// One line per stop, as a person reads it ("  -6 EV: 60 x 100 us, mean code 9.7").
  std::function<void(const std::string&)> onStop;
};

struct Sweep {
  /// One frame per stop taken: the lowest stop first, then up to the highest, then each one
  /// below the lowest; each with its exposure (Frame::radianceScale = 1 / exposure).
  std::vector<Frame> frames;
  /// Frames that still showed the old exposure after a change, the most common count over the
  /// stops that showed one; unset when none did.
  std::optional<int> controlDelay;
  bool stopped = false;  ///< ended by stopRequested
};

/// The exposure sweep a calibration reads: one frame per whole stop from `lowest` to `highest`
/// about the locked exposure, each after the camera has taken it (the frame that reports the
/// exposure asked, where the camera reports its exposures; else after `settle` frames), then on
/// below `lowest` while the shortest frame reads no code of kDarkestCode or less, up to 12 stops
/// more, to the control's limit. A stop the control clamps to the last one's exposure is not
/// taken; one a camera reports at the last stop's exposure (its frame time the longest it can
/// take) neither. The control delay: after each change, the frames that still show the old
/// exposure (the camera's report, else the first frame whose mean code moved by more than 4% and
/// a code; a one-stop change moves it far more unless the frame clips or is black, and such a
/// stop says nothing). Throws lp::Error naming the camera when the stream ends, or when the
/// camera ignores its exposure control (fewer than 3 stops, or the mean code moves by under 8
/// across the sweep).
Sweep sweepExposures(FrameSource& camera, ExposureControl& control, const SweepOptions& options);

}  // namespace lp
