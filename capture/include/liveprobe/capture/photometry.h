#pragma once
// Photometry: frames to linear radiance. 8-bit frames are decoded from sRGB (or a power-law
// gamma) through a 256-entry lookup table that includes the exposure scale; float frames are
// linear already and only scaled. Saturated 8-bit values (a channel at 255) are counted: their
// true radiance is unknown, so the lighting from them is a lower bound.
#include <array>
#include <cstddef>

#include "liveprobe/capture/image.h"
#include "liveprobe/frame/frame.h"

namespace lp {

struct Photometry {
  float gamma = 0.0f;     ///< 0: the sRGB curve; otherwise linear = code^gamma
  float exposure = 1.0f;  ///< linear radiance multiplier
};

class Linearizer {
 public:
  explicit Linearizer(const Photometry& p = {});
  /// Converts `frame` to linear RGB in `out` (resized as needed); returns the number of
  /// saturated channel values, at 255 (0 for float frames).
  std::size_t convert(const Frame& frame, Image& out) const;
  const std::array<float, 256>& table() const { return lut_; }
  float exposure() const { return exposure_; }

 private:
  std::array<float, 256> lut_;
  float exposure_;
};

/// Channel values at 255 in an 8-bit frame (what convert() returns too).
std::size_t countSaturated(const Frame& frame);

}  // namespace lp
