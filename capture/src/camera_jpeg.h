#pragma once
// What a V4L2 camera's MJPEG, a network camera's motion JPEG and a JPEG file share (private to
// capture): the frame size its header declares, the JPEG decoded at a reduced scale, and a
// decoded BGR image stored as an 8-bit frame.
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <utility>

#include "liveprobe/frame/frame.h"

namespace lp {

/// The frame size (width, height) a JPEG's SOF segment declares, read before any decoding: a
/// corrupt header could otherwise make the decoder allocate for a frame of any size. None when
/// `data` does not reach an SOF segment. Markers per ITU T.81, B.1.1.
std::optional<std::pair<int, int>> jpegFrameSize(const std::uint8_t* data, std::size_t bytes);

/// The JPEG in `data` decoded to BGR8 at 1/`reduce` scale (1, 2, 4 or 8: libjpeg's DCT scaling,
/// which rounds up); empty when it does not start with the SOI marker or does not decode.
cv::Mat decodeCameraJpeg(const std::uint8_t* data, std::size_t bytes, int reduce);

/// `bgr` (CV_8UC3) as an 8-bit frame; an empty image leaves an empty frame (width 0).
void storeBgrFrame(const cv::Mat& bgr, Frame& f);

}  // namespace lp
