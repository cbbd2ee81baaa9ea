#pragma once
// A camera's response: the linear light each 8-bit code stands for, as a merge reads it (sRGB, a
// gamma, or a calibration's curve, liveprobe/hdr/calibrate.h), and its JSON file.
#include <array>
#include <functional>
#include <optional>
#include <string>

namespace lp {

/// A camera's response, inverted: the linear exposure (1 at the sensor's clip) each 8-bit code
/// stands for, per channel in R, G, B order. Monotonic non-decreasing in the code.
struct CameraResponse {
  std::array<std::array<float, 256>, 3> linear{};
  std::string name;  ///< "sRGB", "gamma 2.6", or the file it came from
  /// The codes a calibration read in every channel, from..to (the curve beyond continues the
  /// read part's shape, unmeasured): a merge counts no reading outside them. 0..255 for a
  /// response known whole.
  int readFrom = 0, readTo = 255;
  /// Frames a calibration saw at the old exposure after the control was set (the camera's
  /// control delay, as liveprobe receives frames); unknown for a response not calibrated.
  std::optional<int> controlDelay;

  static CameraResponse srgb();
  static CameraResponse gamma(float g);
  /// Reads a response written by json(). Throws lp::Error naming `path` when it is missing, is not
  /// a response, or is not monotonic.
  static CameraResponse load(const std::string& path);
  /// Parses json() text; `name` is what errors call it.
  static CameraResponse parse(const std::string& text, const std::string& name);
  /// {"response": [[256 R], [256 G], [256 B]], "read": [from, to], "control_delay_frames": N}:
  /// linear exposure per code, normalised so that the green channel's power law reaches 1 at
  /// code 255; "read" only where it is not 0..255, the delay only where it was measured.
  std::string json() const;
  /// The first code (and channel) at which the curve falls, or -1 when it never does.
  int firstDecrease(int* channel = nullptr) const;
};

/// The power law linear = atClip (code / 255)^gamma nearest to a curve over codes 32..240 (least
/// squares in log-log): what a response is like, and where it reaches code 255.
struct PowerLaw {
  double gamma = 1, atClip = 1;
};
PowerLaw fitPowerLaw(const std::function<double(int)>& linear);

/// The codes a calibration answers for: from kDarkestCode to kBrightestCode, each within 3% on a
/// scene that reaches them (the codes outside continue the curve).
inline constexpr int kDarkestCode = 4, kBrightestCode = 250;

}  // namespace lp
