#pragma once
// Frames and the one small interface of the sources that produce them (still images, image
// sequences, cube-face sets, video files, a synthetic sky, V4L2 cameras: liveprobe::capture,
// whose factory is openSource() in liveprobe/capture/open_source.h).
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/projector.h"

namespace lp {

/// One frame. Exactly one of the two buffers is filled, by `format`: the projector's pixel format
/// (liveprobe/sh/projector.h), of which frames hold two, BgrU8 (8-bit, display-encoded: sRGB or
/// a gamma, in OpenCV's channel order) and RgbF32 (linear radiance).
struct Frame {
  std::uint64_t sequence = 0;  ///< frame number at the source; a gap means frames were lost
  double timestamp = 0.0;      ///< seconds since the first frame of the source
  int width = 0, height = 0;
  PanoramaFormat format = PanoramaFormat::RgbF32;
  std::vector<std::uint8_t> bgr8;  ///< width * height * 3 (BgrU8)
  std::vector<float> rgb;          ///< width * height * 3 (RgbF32)
  // Per-frame metadata, as in force for this frame (after libcamera's per-request metadata):
  /// Linear radiance = decoded 8-bit value * this: a camera's 1 / exposure time, a recording's
  /// stored 1 / exposure. 1 for float frames and for sources without an exposure.
  double radianceScale = 1.0;
  /// The driver's capture time, CLOCK_MONOTONIC seconds (a camera's buffer timestamp); < 0 when
  /// the source has none. Comparable with clock_gettime(CLOCK_MONOTONIC), so latency is measurable.
  double captureTime = -1.0;
  /// A camera's exposure time (in 100 us, V4L2_CID_EXPOSURE_ABSOLUTE) and gain for this frame.
  std::optional<std::int32_t> exposure100us, gain;
  /// The camera reported this frame's exposure time itself (UVC metadata): exposure100us and
  /// radianceScale are what it was taken with, not what the control was last set to.
  bool exposureReported = false;
};

/// Now on CLOCK_MONOTONIC, in seconds: the clock of Frame::captureTime.
double monotonicSeconds();

/// A frame rate as a person writes it: "30 fps", "29.97 fps", "0.5 fps" (four significant digits
/// at most, no trailing zeros).
std::string formatFps(double fps);

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// The next frame; false at the end of the stream. Throws lp::Error on a fatal failure.
  virtual bool next(Frame& frame) = 0;
  /// Back to the first frame (a looping replay); false if the source cannot.
  virtual bool rewind() = 0;
  virtual std::string describe() const = 0;
  /// Nominal frame rate, 0 if unknown.
  virtual double fps() const = 0;
  /// Frames that could not be decoded and were skipped.
  virtual std::size_t skippedFrames() const { return 0; }
  /// Why the stream ended, when it ended early (a truncated file); empty otherwise.
  virtual std::string endReason() const { return {}; }
  /// The layout the source's frames are in, where the source itself knows it (six cube faces
  /// make a horizontal cross); empty where only the user can say (any single image or video).
  virtual std::optional<Layout> layout() const { return std::nullopt; }
  /// Frames from the first to the end, where the source knows it (a file: a video's own count,
  /// a sequence's files); -1 for an endless source (synthetic, a camera) or an unknown length.
  virtual std::int64_t frameCount() const { return -1; }
  /// Times the source lost its stream and opened it again (a network camera); 0 for the rest.
  virtual std::size_t reconnects() const { return 0; }
  /// Frames the source itself replaced by newer ones before next() took them (a network
  /// camera's reader keeps only the newest); 0 for the rest.
  virtual std::size_t staleFrames() const { return 0; }
  /// While the source is without its stream (a network camera reconnecting), what it waits for
  /// in a few words ("reconnecting for 3.2 s: connection refused"); empty otherwise.
  /// Thread-safe: asked while another thread waits in next().
  virtual std::string waitingFor() const { return {}; }
  /// Ends a next() that waits (a network stream between reconnection tries): it returns false.
  /// Thread-safe; called by whoever stops the thread that reads the source.
  virtual void interrupt() {}
};

}  // namespace lp
