#pragma once
// 8-bit sRGB frames of the project's synthetic sky, for tests that need camera-like input.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "liveprobe/capture/image.h"
#include "liveprobe/capture/open_source.h"
#include "liveprobe/frame/frame.h"

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

// Writes the emulator's modes: FOURCC_WxH folders of sky frames (JPEG for MJPG, PNG otherwise).
inline void makeModes(const std::filesystem::path& dir, const std::vector<std::string>& modes,
                      int frames = 10) {
  for (const auto& m : modes) {
    int w = 0, h = 0;
    std::sscanf(m.c_str() + 5, "%dx%d", &w, &h);
    std::filesystem::create_directories(dir / m);
    for (int i = 0; i < frames; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "%04d.%s", i, m.rfind("MJPG", 0) == 0 ? "jpg" : "png");
      if (!cv::imwrite((dir / m / name).string(), lpt::skyFrame8(w, h, i * 0.4)))
        throw std::runtime_error("cannot write " + (dir / m / name).string());
    }
  }
}

}  // namespace lpt
