#pragma once
// Network streams as frame sources, read through FFmpeg (libavformat, libavcodec, libswscale):
// rtsp:// (TCP, or UDP on request), http(s):// (motion JPEG multipart, or any stream or file
// FFmpeg's demuxers take), srt://, udp://, rtp://, tcp://. Motion JPEG is decoded by the same
// JPEG decoder as a V4L2 camera's MJPEG (and scaled the same way, --mjpeg-reduce); everything
// else by libavcodec, converted to 8-bit BGR.
//
// A camera (`Mode::Latest`) is read on its own thread with low-latency settings (no demuxer
// buffering beyond what the protocol needs, no frame-threaded decoding): the newest decoded frame
// waits for next(), an older one not taken is dropped and counted, as a V4L2 camera's are. When
// the stream ends or stalls past the timeout it is reopened with a backoff (up to `reconnect`
// seconds between tries; 0 ends the stream instead), each try said through `say`. A file on a
// server (`Mode::Every`) is read frame by frame, like a local video.
//
// Credentials never leave this module: a URL is only ever shown through redactUrl().
#include <cstddef>
#include <functional>
#include <memory>
#include <string>

#include "liveprobe/frame/frame.h"

namespace lp {

/// Whether `spec` names a network stream (a URL with a scheme FFmpeg reads from the network).
bool isNetworkUrl(const std::string& spec);

/// The URL with its password (user:PASSWORD@) and its secret query values (passphrase, password,
/// pass, pwd, key, token, secret, auth) replaced by "***".
std::string redactUrl(const std::string& url);

struct NetworkSettings {
  enum class Mode : std::uint8_t {
    Latest,  ///< a camera: its own reader thread, the newest frame kept, reconnecting
    Every,   ///< a file or a recording on a server: every frame, in order
  };
  std::string url;
  Mode mode = Mode::Latest;
  int timeoutMs = 2000;  ///< connecting, and the longest wait for a frame
  /// The longest wait between reconnection tries, in seconds (Latest; 0: a stream that ends or
  /// stalls ends the run).
  double reconnectSeconds = 10;
  bool rtspUdp = false;  ///< RTSP over UDP instead of TCP (interleaved)
  int mjpegReduce = 1;   ///< decode motion JPEG at 1/2, 1/4 or 1/8 scale
  /// Lines about the stream's connection (a stall, a reconnect), one per event.
  std::function<void(const std::string&)> say;
  /// Polled while next() waits (a reconnect, a stall): true ends the stream (the app's signal
  /// flag).
  std::function<bool()> interrupted;
};

/// Opens the stream; throws lp::Error naming the (redacted) URL and what failed (refused, not
/// found, unauthorized, timed out, not a video) within the timeout.
std::unique_ptr<FrameSource> openNetwork(NetworkSettings settings);

}  // namespace lp
