#pragma once
#include <cstdio>
#include <stdexcept>
#include <string>

namespace lp {

/// The one error type of liveprobe's libraries (the SH core, capture, I/O): a one-line message that
/// names the input and what is wrong with it ("grace.exr: 3 pixels are NaN or Inf"). app/ prints it
/// and exits non-zero.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A number as a person writes it in a message: up to `digits` significant digits, no trailing
/// zeros (30, 25.13, 0.02, 1e+30).
inline std::string formatNumber(double v, int digits = 4) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

}  // namespace lp
