#pragma once
// A linear-RGB float image in memory: the one image type of liveprobe (reading and writing files
// is liveprobe::capture's, liveprobe/capture/image.h).
#include <cstddef>
#include <vector>

namespace lp {

/// An owning linear-RGB float image (3 floats per pixel, rows top to bottom).
struct Image {
  int width = 0;
  int height = 0;
  std::vector<float> rgb;

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgb(std::size_t(w) * h * 3, 0.0f) {}
  float* pixel(int x, int y) { return rgb.data() + (std::size_t(y) * width + x) * 3; }
  const float* pixel(int x, int y) const { return rgb.data() + (std::size_t(y) * width + x) * 3; }
};

}  // namespace lp
