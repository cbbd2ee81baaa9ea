// The Highway targets every liveprobe kernel is compiled for: the paths of liveprobe/sh/simd.h.
// Included by a kernel source before <hwy/foreach_target.h> (so no #pragma once: Highway
// re-includes the source once per target).
//
// Scalar (Highway's SCALAR or EMU128 target), AVX2, AVX-512 and NEON. SVE is left out: its vectors
// are sizeless and cannot sit in arrays of vectors, and no machine here runs it. AVX3_DL adds
// nothing we use.
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS \
  (HWY_SSSE3 | HWY_SSE4 | HWY_AVX3_DL | HWY_SVE | HWY_SVE2 | HWY_SVE_256 | HWY_SVE2_128)
#endif
#ifndef HWY_COMPILE_ALL_ATTAINABLE
#define HWY_COMPILE_ALL_ATTAINABLE  // keep the scalar path beside the best one
#endif
