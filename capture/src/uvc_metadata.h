#pragma once
// A UVC camera's metadata node, streamed beside its video node: per frame, the payload header the
// camera sent, matched to the video frame by sequence number (uvcvideo gives a frame's metadata
// buffer the frame's sequence). Microsoft's UVC 1.5 extensions put capture statistics in that
// header, among them the exposure time the frame was actually taken with; Linux hands the whole
// header over as V4L2_META_FMT_UVC_MSXU_1_5 (or V4L2_META_FMT_D4XX on Intel RealSense cameras,
// the same layout). Written to docs.kernel.org's metafmt-uvc and metafmt-uvc-msxu-1-5 pages.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "liveprobe/capture/v4l2.h"
#include "v4l2_device.h"

namespace lp {

class UvcMetadata {
 public:
  /// Opens `path`, checks that it is a metadata node on bus `bus` (the video node's) that offers a
  /// format carrying the whole payload header, and streams it. Throws lp::Error with one line
  /// naming `path` and what is missing.
  UvcMetadata(const std::string& path, const std::string& bus);
  ~UvcMetadata();
  UvcMetadata(const UvcMetadata&) = delete;
  UvcMetadata& operator=(const UvcMetadata&) = delete;

  /// The exposure time, in seconds, the camera reported for the video frame with this sequence
  /// number; waits up to `timeoutMs` for its block. nullopt when the block never came or carried
  /// no exposure.
  std::optional<double> exposureOf(std::uint32_t sequence, int timeoutMs);
  const std::string& path() const { return path_; }

 private:
  void drain();
  std::string path_;
  UniqueFd fd_;
  std::unique_ptr<V4l2Queue> queue_;                     ///< destroyed before fd_
  std::map<std::uint32_t, std::optional<double>> seen_;  ///< by sequence, the newest few
};

}  // namespace lp
