#pragma once
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

}  // namespace lp
