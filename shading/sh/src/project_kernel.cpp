// Projection kernels, written once with Highway and compiled for each SIMD path (foreach_target
// re-includes this file once per target, each time inside hwy::HWY_NAMESPACE). The paths are
// picked by our own table below rather than HWY_DYNAMIC_DISPATCH, so LIVEPROBE_SIMD can force one
// and the core needs Highway's headers only, not its library.

#include "liveprobe/sh/simd_targets.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "project_kernel.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
//
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

#include "project_kernel.h"

HWY_BEFORE_NAMESPACE();
namespace lp::kernel {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using DF = hn::ScalableTag<float>;
using VF = hn::Vec<DF>;

// acc lanes of coefficient k, channel c.
inline float* laneOf(LaneSums& acc, int k, int c) { return acc.v + (3 * k + c) * kMaxLanes; }

// With Peak, *peak also receives the row's largest value, taken from the vectors the sums load
// anyway (a second pass read a 3840-pixel row back from L2: 0.3 ms a frame).
template <bool Peak>
void EquirectRowImpl(const EquirectTables& t, const float* HWY_RESTRICT row, int i, LaneSums& acc,
                     float* peak) {
  const DF d;
  const int n = int(hn::Lanes(d));
  const float* HWY_RESTRICT c0 = t.col[0].data();
  const float* HWY_RESTRICT c1 = t.col[1].data();
  const float* HWY_RESTRICT c2 = t.col[2].data();
  const float* HWY_RESTRICT c3 = t.col[3].data();
  const float* HWY_RESTRICT c4 = t.col[4].data();
  // s[k][c]: column sum k of channel c (in the row's channel order).
  VF s00 = hn::Zero(d), s01 = s00, s02 = s00, s10 = s00, s11 = s00, s12 = s00, s20 = s00, s21 = s00,
     s22 = s00, s30 = s00, s31 = s00, s32 = s00, s40 = s00, s41 = s00, s42 = s00;
  VF m = hn::Set(d, -HUGE_VALF);
  float tail = -HUGE_VALF;
  const auto track = [&](VF x, VF y, VF z) HWY_ATTR {
    if constexpr (Peak) m = hn::Max(m, hn::Max(x, hn::Max(y, z)));
  };
  const int w = t.width;
  if (w % 2 == 0) {
    // Pixels half a turn apart (j and j + W/2) share the column integrals up to sign: 1, cos 2p
    // and sin 2p repeat after half a turn, cos p and sin p change sign. So the sum a + b takes
    // the even weights and a - b the odd ones: 15 multiply-adds per pair of pixels, not per pixel.
    const int half = w / 2;
    auto pair = [&](const float* pa, const float* pb, int j, bool whole) HWY_ATTR {
      VF ax, ay, az, bx, by, bz;
      hn::LoadInterleaved3(d, pa, ax, ay, az);
      hn::LoadInterleaved3(d, pb, bx, by, bz);
      if (whole) track(ax, ay, az), track(bx, by, bz);
      const VF sx = hn::Add(ax, bx), sy = hn::Add(ay, by), sz = hn::Add(az, bz);
      const VF dx = hn::Sub(ax, bx), dy = hn::Sub(ay, by), dz = hn::Sub(az, bz);
      const VF w0 = hn::LoadU(d, c0 + j);
      s00 = hn::MulAdd(w0, sx, s00), s01 = hn::MulAdd(w0, sy, s01), s02 = hn::MulAdd(w0, sz, s02);
      const VF w3 = hn::LoadU(d, c3 + j);
      s30 = hn::MulAdd(w3, sx, s30), s31 = hn::MulAdd(w3, sy, s31), s32 = hn::MulAdd(w3, sz, s32);
      const VF w4 = hn::LoadU(d, c4 + j);
      s40 = hn::MulAdd(w4, sx, s40), s41 = hn::MulAdd(w4, sy, s41), s42 = hn::MulAdd(w4, sz, s42);
      const VF w1 = hn::LoadU(d, c1 + j);
      s10 = hn::MulAdd(w1, dx, s10), s11 = hn::MulAdd(w1, dy, s11), s12 = hn::MulAdd(w1, dz, s12);
      const VF w2 = hn::LoadU(d, c2 + j);
      s20 = hn::MulAdd(w2, dx, s20), s21 = hn::MulAdd(w2, dy, s21), s22 = hn::MulAdd(w2, dz, s22);
    };
    int j = 0;
    if (w >= 1024) {
      // A large row streams from memory in two places at once (j and j + W/2), which the
      // hardware prefetchers follow late: ask for both 6 KB ahead.
      constexpr int kAhead = 6144;
      for (; j + n <= half; j += n) {
        const char* a = reinterpret_cast<const char*>(row + 3 * j) + kAhead;
        const char* b = reinterpret_cast<const char*>(row + 3 * (j + half)) + kAhead;
        for (int line = 0; line < 12 * n; line += 64)
          __builtin_prefetch(a + line), __builtin_prefetch(b + line);
        pair(row + 3 * j, row + 3 * (j + half), j, true);
      }
    }
    for (; j + n <= half; j += n) pair(row + 3 * j, row + 3 * (j + half), j, true);
    if (j < half) {  // the last pairs, zero-padded (zero pixels: the weights past W/2 add nothing)
      alignas(64) float ta[3 * kMaxLanes] = {}, tb[3 * kMaxLanes] = {};
      std::memcpy(ta, row + 3 * j, sizeof(float) * 3 * std::size_t(half - j));
      std::memcpy(tb, row + 3 * (j + half), sizeof(float) * 3 * std::size_t(half - j));
      if constexpr (Peak)  // the padding is not the row's: these pixels one at a time
        for (int q = 0; q < 3 * (half - j); ++q) tail = std::max({tail, ta[q], tb[q]});
      pair(ta, tb, j, false);
    }
  } else {
    auto step = [&](const float* px, int j, bool whole) HWY_ATTR {
      VF x, y, z;
      hn::LoadInterleaved3(d, px, x, y, z);
      if (whole) track(x, y, z);
      const VF w0 = hn::LoadU(d, c0 + j), w1 = hn::LoadU(d, c1 + j), w2 = hn::LoadU(d, c2 + j),
               w3 = hn::LoadU(d, c3 + j), w4 = hn::LoadU(d, c4 + j);
      s00 = hn::MulAdd(w0, x, s00), s01 = hn::MulAdd(w0, y, s01), s02 = hn::MulAdd(w0, z, s02);
      s10 = hn::MulAdd(w1, x, s10), s11 = hn::MulAdd(w1, y, s11), s12 = hn::MulAdd(w1, z, s12);
      s20 = hn::MulAdd(w2, x, s20), s21 = hn::MulAdd(w2, y, s21), s22 = hn::MulAdd(w2, z, s22);
      s30 = hn::MulAdd(w3, x, s30), s31 = hn::MulAdd(w3, y, s31), s32 = hn::MulAdd(w3, z, s32);
      s40 = hn::MulAdd(w4, x, s40), s41 = hn::MulAdd(w4, y, s41), s42 = hn::MulAdd(w4, z, s42);
    };
    int j = 0;
    for (; j + n <= w; j += n) step(row + 3 * j, j, true);
    if (j < w) {  // the last pixels, zero-padded (the column tables are zero past the width)
      alignas(64) float last[3 * kMaxLanes] = {};
      std::memcpy(last, row + 3 * j, sizeof(float) * 3 * std::size_t(w - j));
      if constexpr (Peak)
        for (int q = 0; q < 3 * (w - j); ++q) tail = std::max(tail, last[q]);
      step(last, j, false);
    }
  }
  // acc[k][c] += rowFactor(k) * s[col(k)][c], written out with constant indices so the sums stay
  // in registers.
  const auto add = [&](int k, float f, VF r, VF g, VF b) HWY_ATTR {
    const VF fv = hn::Set(d, f);
    float* a = laneOf(acc, k, 0);
    hn::Store(hn::MulAdd(fv, r, hn::Load(d, a)), d, a);
    hn::Store(hn::MulAdd(fv, g, hn::Load(d, a + kMaxLanes)), d, a + kMaxLanes);
    hn::Store(hn::MulAdd(fv, b, hn::Load(d, a + 2 * kMaxLanes)), d, a + 2 * kMaxLanes);
  };
  const auto& R = t.row;
  add(0, R[0][i], s00, s01, s02);  // L00  = k0 R1 S1
  add(1, R[2][i], s20, s21, s22);  // L1-1 = k1 Rs Ssin
  add(2, R[1][i], s00, s01, s02);  // L10  = k1 Rc S1
  add(3, R[2][i], s10, s11, s12);  // L11  = k1 Rs Scos
  add(4, R[4][i], s40, s41, s42);  // L2-2 = k4 Rs2 Ssin2
  add(5, R[3][i], s20, s21, s22);  // L2-1 = k2 Rsc Ssin
  add(6, R[5][i], s00, s01, s02);  // L20  = k3 R3 S1
  add(7, R[3][i], s10, s11, s12);  // L21  = k2 Rsc Scos
  add(8, R[4][i], s30, s31, s32);  // L22  = k4 Rs2 Scos2
  if constexpr (Peak) *peak = std::max(tail, hn::GetLane(hn::MaxOfLanes(d, m)));
}

void EquirectRow(const EquirectTables& t, const float* HWY_RESTRICT row, int i, LaneSums& acc,
                 float* peak) {
  if (peak)
    EquirectRowImpl<true>(t, row, i, acc, peak);
  else
    EquirectRowImpl<false>(t, row, i, acc, nullptr);
}

// The products of SampleStreams from a pixel's four stream values.
template <int K>
HWY_INLINE VF Product(VF q, VF x, VF y, VF z, const VF (&up)[3]) {
  if constexpr (K == 0) return hn::Mul(q, q);
  if constexpr (K == 1) return hn::Mul(q, y);
  if constexpr (K == 2) return hn::Mul(q, z);
  if constexpr (K == 3) return hn::Mul(q, x);
  if constexpr (K == 4) return hn::Mul(x, y);
  if constexpr (K == 5) return hn::Mul(y, z);
  if constexpr (K == 6) return hn::MulSub(hn::Add(z, hn::Add(z, z)), z, hn::Mul(q, q));
  if constexpr (K == 7) return hn::Mul(x, z);
  if constexpr (K == 8) return hn::Mul(hn::Sub(x, y), hn::Add(x, y));
  if constexpr (K == 9) {
    const VF c = hn::MulAdd(x, up[0], hn::MulAdd(y, up[1], hn::Mul(z, up[2])));
    return hn::Mul(hn::ZeroIfNegative(c), q);
  }
}

// Ten products times three channels is 30 accumulators, more than 16 registers hold (32 on
// AVX-512): each run of pixels is swept once per group of products [K0, K1), the later sweeps
// reading the run from L1. Each product is made from the pixel's streams (16 bytes a pixel,
// where a table of nine weights would be 36).
template <int K0, int K1>
void SampleSweep(const float* HWY_RESTRICT r, const float* HWY_RESTRICT g,
                 const float* HWY_RESTRICT b, std::size_t count, const SampleStreams& s,
                 const float* up, double* out) {
  constexpr int kN = K1 - K0;
  const DF d;
  const std::size_t n = hn::Lanes(d);
  const VF u[3] = {hn::Set(d, up[0]), hn::Set(d, up[1]), hn::Set(d, up[2])};
  VF acc[kN][3];
  for (auto& a : acc)
    for (auto& v : a) v = hn::Zero(d);
  for (std::size_t i = 0; i < count; i += n) {
    const VF vr = hn::Load(d, r + i), vg = hn::Load(d, g + i), vb = hn::Load(d, b + i);
    const VF q = hn::LoadU(d, s.q + i), x = hn::LoadU(d, s.x + i), y = hn::LoadU(d, s.y + i),
             z = hn::LoadU(d, s.z + i);
    [&]<std::size_t... K>(std::index_sequence<K...>) HWY_ATTR {
      ((acc[K][0] = hn::MulAdd(Product<K0 + int(K)>(q, x, y, z, u), vr, acc[K][0]),
        acc[K][1] = hn::MulAdd(Product<K0 + int(K)>(q, x, y, z, u), vg, acc[K][1]),
        acc[K][2] = hn::MulAdd(Product<K0 + int(K)>(q, x, y, z, u), vb, acc[K][2])),
       ...);
    }
    (std::make_index_sequence<kN>{});
  }
  for (int k = 0; k < kN; ++k)
    for (int c = 0; c < 3; ++c)
      out[3 * (K0 + k) + c] += double(hn::GetLane(hn::SumOfLanes(d, acc[k][c])));
}

void SampleSums(const float* rgb, std::size_t n, SampleStreams s, const float* up, double* out) {
  // Runs of 512 pixels made planar once (6 KB, zero past the run's end: the streams are
  // readable there), then read from L1 by each sweep.
  constexpr std::size_t kRun = 512;
  const DF d;
  const std::size_t lanes = hn::Lanes(d);
  alignas(64) float r[kRun], g[kRun], b[kRun];
  for (std::size_t b0 = 0; b0 < n; b0 += kRun) {
    const std::size_t count = std::min(n - b0, kRun);
    const std::size_t whole = count / lanes * lanes;
    const float* px = rgb + 3 * b0;
    for (std::size_t i = 0; i < whole; i += lanes) {
      VF vr, vg, vb;
      hn::LoadInterleaved3(d, px + 3 * i, vr, vg, vb);
      hn::Store(vr, d, r + i), hn::Store(vg, d, g + i), hn::Store(vb, d, b + i);
    }
    std::size_t padded = whole;
    if (whole < count) {
      padded += lanes;
      for (std::size_t i = whole; i < padded; ++i) {
        const bool in = i < count;
        r[i] = in ? px[3 * i] : 0.0f, g[i] = in ? px[3 * i + 1] : 0.0f,
        b[i] = in ? px[3 * i + 2] : 0.0f;
      }
    }
    const SampleStreams at{s.q + b0, s.x + b0, s.y + b0, s.z + b0};
#if HWY_TARGET == HWY_AVX3
    SampleSweep<0, 5>(r, g, b, padded, at, up, out);
    SampleSweep<5, 10>(r, g, b, padded, at, up, out);
#else
    SampleSweep<0, 3>(r, g, b, padded, at, up, out);
    SampleSweep<3, 6>(r, g, b, padded, at, up, out);
    SampleSweep<6, 8>(r, g, b, padded, at, up, out);
    SampleSweep<8, 10>(r, g, b, padded, at, up, out);
#endif
  }
}

// Table lookups. AVX2: one at a time, each a scalar load and store (a gather, GatherIndex,
// measured slower: 17.6 against 13.2 ms for a 3840x1920 frame on one thread; fusing the lookups
// into the projection's loads stalls on store forwarding). AVX-512: the table held in registers
// (below); the compiler's own vectorisation there (scalar loads inserted lane by lane) made the
// 8-bit projection a fifth slower than AVX2's, so the scalar tail is kept from it.
#if HWY_COMPILER_GCC_ACTUAL && HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
__attribute__((optimize("no-tree-vectorize")))
#endif
void DecodeU8(const std::uint8_t* HWY_RESTRICT src, const float* HWY_RESTRICT lut,
              float* HWY_RESTRICT dst, std::size_t n) {
  std::size_t i = 0;
#if HWY_TARGET == HWY_AVX3
  // The 256-entry table in 16 registers: 8 two-register permutes look up 32 entries each by a
  // code's low 5 bits, and bits 5-7 choose among them in three blends; 16 codes a step.
  __m512 t[16];
  for (int k = 0; k < 16; ++k) t[k] = _mm512_loadu_ps(lut + 16 * k);
  for (; i + 16 <= n; i += 16) {
    const __m512i idx =
        _mm512_cvtepu8_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(src + i)));
    __m512 r[8];
    for (int p = 0; p < 8; ++p) r[p] = _mm512_permutex2var_ps(t[2 * p], idx, t[2 * p + 1]);
    const __mmask16 b5 = _mm512_test_epi32_mask(idx, _mm512_set1_epi32(32));
    const __mmask16 b6 = _mm512_test_epi32_mask(idx, _mm512_set1_epi32(64));
    const __mmask16 b7 = _mm512_test_epi32_mask(idx, _mm512_set1_epi32(128));
    const __m512 a0 = _mm512_mask_blend_ps(b5, r[0], r[1]),
                 a1 = _mm512_mask_blend_ps(b5, r[2], r[3]);
    const __m512 a2 = _mm512_mask_blend_ps(b5, r[4], r[5]),
                 a3 = _mm512_mask_blend_ps(b5, r[6], r[7]);
    const __m512 c0 = _mm512_mask_blend_ps(b6, a0, a1), c1 = _mm512_mask_blend_ps(b6, a2, a3);
    _mm512_storeu_ps(dst + i, _mm512_mask_blend_ps(b7, c0, c1));
  }
#endif
  for (; i < n; ++i) dst[i] = lut[src[i]];
}

void DecodeF16(const std::uint16_t* HWY_RESTRICT src, float* HWY_RESTRICT dst, std::size_t n) {
  const DF d;
  const hn::Rebind<hwy::float16_t, DF> dh;
  const std::size_t lanes = hn::Lanes(d);
  const auto* h = reinterpret_cast<const hwy::float16_t*>(src);
  std::size_t i = 0;
  for (; i + lanes <= n; i += lanes) hn::StoreU(hn::PromoteTo(d, hn::LoadU(dh, h + i)), d, dst + i);
  if (i < n) {
    alignas(64) hwy::float16_t in[kMaxLanes] = {};
    alignas(64) float outTail[kMaxLanes];
    std::memcpy(in, h + i, 2 * (n - i));
    hn::Store(hn::PromoteTo(d, hn::Load(dh, in)), d, outTail);
    std::memcpy(dst + i, outTail, 4 * (n - i));
  }
}

float MaxOf(const float* HWY_RESTRICT p, std::size_t n) {
  const DF d;
  const std::size_t lanes = hn::Lanes(d);
  VF m = hn::Set(d, -HUGE_VALF);
  std::size_t i = 0;
  for (; i + lanes <= n; i += lanes) m = hn::Max(m, hn::LoadU(d, p + i));
  float out = hn::GetLane(hn::MaxOfLanes(d, m));
  for (; i < n; ++i) out = std::max(out, p[i]);
  return out;
}

// NOLINTNEXTLINE(cert-err58-cpp): a constant table, no allocation
const Kernels kKernels = {&EquirectRow, &SampleSums, &DecodeU8, &DecodeF16, &MaxOf};

}  // namespace HWY_NAMESPACE
}  // namespace lp::kernel
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#if HWY_ARCH_X86
#include <cpuid.h>
#endif

#include <atomic>
#include <cstdlib>
#include <mutex>
#include <string>

#include "liveprobe/sh/error.h"
#include "liveprobe/sh/simd.h"

namespace lp::kernel {
namespace {

struct Path {
  const char* name;
  std::int64_t target;
  const Kernels* kernels;
};

// Compiled paths, worst first.
std::vector<Path> compiledPaths() {
  std::vector<Path> p;
#if HWY_TARGETS & HWY_EMU128
  p.push_back({"scalar", HWY_EMU128, &N_EMU128::kKernels});
#elif HWY_TARGETS & HWY_SCALAR
  p.push_back({"scalar", HWY_SCALAR, &N_SCALAR::kKernels});
#endif
#if HWY_TARGETS & HWY_NEON
  p.push_back({"neon", HWY_NEON, &N_NEON::kKernels});
#endif
#if HWY_TARGETS & HWY_AVX2
  p.push_back({"avx2", HWY_AVX2, &N_AVX2::kKernels});
#endif
#if HWY_TARGETS & HWY_AVX3
  p.push_back({"avx512", HWY_AVX3, &N_AVX3::kKernels});
#endif
  return p;
}

#if HWY_ARCH_X86
// F16C: CPUID leaf 1, ECX bit 29 (clang 14's __builtin_cpu_supports does not know the name).
bool cpuHasF16c() {
  unsigned a = 0, b = 0, c = 0, d = 0;
  return __get_cpuid(1, &a, &b, &c, &d) && (c & (1u << 29)) != 0;
}
#endif

// What Highway's targets require of the CPU (hwy/targets.cc), asked of the compiler's runtime.
bool cpuRuns(std::int64_t target) {
#if HWY_ARCH_X86
  if (target == HWY_AVX2)
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
           __builtin_cpu_supports("bmi2") && cpuHasF16c();
  if (target == HWY_AVX3)
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
           __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") &&
           __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#endif
  (void)target;
  return true;  // scalar everywhere; NEON is the aarch64 baseline
}

std::vector<Path> runnablePaths() {
  std::vector<Path> out;
  for (const Path& p : compiledPaths())
    if (cpuRuns(p.target)) out.push_back(p);
  return out;
}

const Path& pick(std::string_view name) {
  static const std::vector<Path> paths = runnablePaths();
  if (name.empty() || name == "native") return paths.back();
  for (const Path& p : paths)
    if (name == p.name) return p;
  std::string have;
  for (const Path& p : paths) have += std::string(have.empty() ? "" : ", ") + p.name;
  bool known = name == "scalar" || name == "avx2" || name == "avx512" || name == "neon";
  throw Error("LIVEPROBE_SIMD=" + std::string(name) +
              (known ? ": this CPU or build cannot run it (it has " + have + ")"
                     : ": unknown path (expected scalar, avx2, avx512, neon or native)"));
}

std::atomic<const Path*> gActive{nullptr};
std::once_flag gFromEnv;

const Path& activePath() {
  std::call_once(gFromEnv, [] {
    const char* env = std::getenv("LIVEPROBE_SIMD");
    const Path* none = nullptr;
    gActive.compare_exchange_strong(none, &pick(env ? env : ""));
  });
  return *gActive.load();
}

}  // namespace

const Kernels& active() { return *activePath().kernels; }

}  // namespace lp::kernel

namespace lp::simd {

std::vector<std::string> available() {
  std::vector<std::string> out;
  for (const auto& p : kernel::runnablePaths()) out.emplace_back(p.name);
  return out;
}

std::string current() { return kernel::activePath().name; }

void select(std::string_view path) {
  kernel::activePath();  // an invalid LIVEPROBE_SIMD still reports itself first
  kernel::gActive.store(&kernel::pick(path));
}

}  // namespace lp::simd
#endif  // HWY_ONCE
