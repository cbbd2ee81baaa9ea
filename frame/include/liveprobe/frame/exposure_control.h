#pragma once
// The one thing exposure bracketing (liveprobe/hdr/bracketing.h) asks of a camera.
#include <cstdint>
#include <utility>

namespace lp {

/// What bracketing needs of a camera: its exposure time control, in 100 us units (UVC's
/// V4L2_CID_EXPOSURE_ABSOLUTE).
class ExposureControl {
 public:
  virtual ~ExposureControl() = default;
  /// The control's range, {minimum, maximum}. Throws lp::Error (one line) when the camera has
  /// no exposure time control.
  virtual std::pair<std::int32_t, std::int32_t> exposureRange() = 0;
  /// Asks for an exposure time, within the range. Throws lp::Error when the camera refuses it.
  virtual void requestExposure(std::int32_t exposure100us) = 0;
};

}  // namespace lp
