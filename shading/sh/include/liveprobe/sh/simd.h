#pragma once
// Which SIMD instruction set the core's kernels run on. One source (Highway) is compiled for
// every path below; at run time the best one the CPU has is used, unless LIVEPROBE_SIMD names
// another:
//   scalar  portable C++, one lane at a time (Highway's SCALAR or EMU128 target)
//   avx2    x86 AVX2 + FMA (8 floats)
//   avx512  x86 AVX-512 F/VL/DQ/BW (16 floats)
//   neon    Arm NEON (4 floats; the baseline on aarch64)
//   native  the best this CPU has (the default)
#include <string>
#include <string_view>
#include <vector>

namespace lp::simd {

/// The paths compiled into this build that this CPU can run, in order of preference (best last).
std::vector<std::string> available();

/// The path in use. The first call reads LIVEPROBE_SIMD; throws lp::Error if it names no path or
/// one this CPU lacks ("LIVEPROBE_SIMD=avx512: this CPU has scalar, avx2").
std::string current();

/// Switches the path ("native" = the best); throws lp::Error like current(). For tests and
/// benchmarks that compare the paths in one process.
void select(std::string_view path);

}  // namespace lp::simd
