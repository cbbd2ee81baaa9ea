#pragma once
// A libavcodec video decoder for compressed camera streams (H.264, HEVC, anything FFmpeg
// decodes): packets in, BGR8 frames out, converted as OpenCV's FFmpeg reader converts a file's
// frames (swscale, bicubic, its default colour matrix), so a stream and its recording give the
// same numbers. Used by the network cameras and by a V4L2 camera's H.264 or HEVC; FFmpeg stays
// private to it (no FFmpeg header here).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "liveprobe/frame/frame.h"

struct AVCodecParameters;
struct AVPacket;

namespace lp {

class VideoDecoder {
 public:
  /// For a stream FFmpeg's demuxer described. `lowDelay`: slice threads only, and no reordering
  /// delay where the stream has no B-frames (one that has them keeps the delay it needs).
  VideoDecoder(const AVCodecParameters& stream, bool lowDelay);
  /// For a camera's elementary stream ("h264" or "hevc": Annex B, parameter sets in band),
  /// decoded frame by frame as it arrives (a camera's real-time stream has no B-frames).
  explicit VideoDecoder(const std::string& codec);
  ~VideoDecoder();
  VideoDecoder(const VideoDecoder&) = delete;
  VideoDecoder& operator=(const VideoDecoder&) = delete;

  /// Sends one packet, which arrived at `arrival` (seconds, on the caller's clock); its data are
  /// copied. False when the decoder refuses it as damaged: the frames after it are then withheld
  /// until the next key frame, as after lost().
  bool send(const AVPacket& packet, double arrival);
  bool send(const std::uint8_t* data, std::size_t bytes, std::int64_t pts, double arrival);
  /// A packet was lost before the decoder saw it: the frames that follow are withheld until the
  /// next key frame (each may refer to the lost one and carry its damage).
  void lost();
  /// The end of the stream: the frames it still holds come out of receive().
  void drain();

  /// What receive() says of a frame besides its pixels.
  struct Decoded {
    std::int64_t pts = 0;  ///< its packet's pts (best effort; INT64_MIN when unknown)
    double arrival = -1;   ///< its own packet's arrival (a reordering decoder gives it later)
  };
  /// The next frame ready, in `frame` (bgr8, width, height; radianceScale 1; the rest left to
  /// the caller); false when none is. A frame the decoder marks damaged, or one withheld after a
  /// loss, is read past and counted in `damaged`. Throws lp::Error when the decoder fails.
  bool receive(Frame& frame, Decoded& info, std::size_t& damaged);

  const std::string& name() const;  ///< FFmpeg's name of the decoder ("h264")

 private:
  struct Impl;
  std::unique_ptr<Impl> d_;
};

/// FFmpeg's messages are never printed: from the first call on, the last error it logged on each
/// thread is kept to explain a failure in one line.
void keepFfmpegErrors();
/// The last error FFmpeg logged on this thread (empty if none since clearFfmpegError()).
const std::string& lastFfmpegError();
void clearFfmpegError();
/// FFmpeg's text for one of its error codes.
std::string ffmpegErrorText(int code);

}  // namespace lp
