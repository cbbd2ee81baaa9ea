#pragma once
// The yardstick a layout's projection speed is judged against: a plain single-threaded equirect
// projection as a straightforward implementation writes it (plain_loop.cpp, compiled -O3
// -march=native -ffast-math on its own).
#include <array>
#include <vector>

namespace lpbench {

class PlainEquirect {
 public:
  PlainEquirect(int width, int height);
  /// The 27 sums (coefficient-major, then R G B) of a packed float RGB equirect frame.
  std::array<float, 27> project(const float* rgb) const;

 private:
  int width_, height_;
  std::vector<float> sinT_, cosT_, rowAngle_, sinP_, cosP_;
};

}  // namespace lpbench
