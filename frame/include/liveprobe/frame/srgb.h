#pragma once
// The sRGB transfer function: how 8-bit frames encode light unless a camera's response says
// otherwise.

namespace lp {

/// sRGB transfer function, decode (8-bit code value / 255 -> linear) and encode.
float srgbToLinear(float v);
float linearToSrgb(float v);

}  // namespace lp
