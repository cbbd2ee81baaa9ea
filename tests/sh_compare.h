#pragma once
// Coefficients against a truth: the worst of the 27 differences, as a share of the truth's L00
// in its own colour channel (the tests' one accuracy measure for a frame's nine coefficients).
#include <algorithm>
#include <cmath>

#include "liveprobe/sh/sh.h"

namespace lpt {

inline double worstOfL00(const lp::Sh9& got, const lp::Sh9& want) {
  double worst = 0;
  for (int k = 0; k < 9; ++k)
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, std::abs(double(got.c[k][c]) - want.c[k][c]) / want.c[0][c]);
  return worst;
}

}  // namespace lpt
