#pragma once
// An 8-bit BGR image as a camera sends it in YUYV: BT.601 limited range, each pair of pixels
// sharing its chroma (the mean of their colours), what OpenCV's COLOR_YUV2BGR_YUYV inverts. The
// emulated camera streams it; the calibration tests decode it as liveprobe does.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace lpt {

inline std::vector<std::uint8_t> encodeYuyv(const cv::Mat& bgr) {
  std::vector<std::uint8_t> out(std::size_t(bgr.cols) * std::size_t(bgr.rows) * 2);
  const auto luma = [](const cv::Vec3b& c) {
    return std::clamp(16.0 + 0.257 * c[2] + 0.504 * c[1] + 0.098 * c[0], 0.0, 255.0);
  };
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x + 1 < bgr.cols; x += 2) {
      const auto* p = bgr.ptr<cv::Vec3b>(y) + x;
      const double r = (p[0][2] + p[1][2]) / 2.0, g = (p[0][1] + p[1][1]) / 2.0,
                   b = (p[0][0] + p[1][0]) / 2.0;
      const double u = std::clamp(128.0 - 0.148 * r - 0.291 * g + 0.439 * b, 0.0, 255.0);
      const double v = std::clamp(128.0 + 0.439 * r - 0.368 * g - 0.071 * b, 0.0, 255.0);
      std::uint8_t* o = out.data() + (std::size_t(y) * std::size_t(bgr.cols) + std::size_t(x)) * 2;
      o[0] = std::uint8_t(std::lround(luma(p[0]))), o[1] = std::uint8_t(std::lround(u));
      o[2] = std::uint8_t(std::lround(luma(p[1]))), o[3] = std::uint8_t(std::lround(v));
    }
  return out;
}

}  // namespace lpt
