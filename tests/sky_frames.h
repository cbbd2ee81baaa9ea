#pragma once
// 8-bit sRGB frames of the project's synthetic sky, for tests that need camera-like input.
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "capture/frame.h"
#include "capture/image.h"

namespace lpt {

/// The synthetic sky at time t (equirect, W x H) as 8-bit BGR, radiance x 0.1 encoded as sRGB.
inline cv::Mat skyFrame8(int w, int h, double t) {
  std::vector<float> sky;
  lp::renderSyntheticSky(w, h, t, sky);
  cv::Mat bgr(h, w, CV_8UC3);
  for (int p = 0; p < w * h; ++p)
    for (int c = 0; c < 3; ++c)
      bgr.data[3 * p + 2 - c] =
          std::uint8_t(std::lround(255 * lp::linearToSrgb(sky[3 * p + c] * 0.1f)));
  return bgr;
}

}  // namespace lpt
