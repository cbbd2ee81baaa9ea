// Projection kernels. Compiled with reassociation allowed (shading/CMakeLists.txt), so the
// portable loops vectorise; the AVX-512 paths are written with intrinsics because GCC folds the
// weight loads into every FMA, and load ports, not FMA units, then limit the loop.
#include "project_kernel.h"

// GCC 12's own AVX-512 reduction intrinsics trip -Wuninitialized on their internal temporaries
// (a known false positive in avx512fintrin.h); silence it for this file only.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <immintrin.h>

#include <algorithm>
#include <cstring>

namespace lp::kernel {

namespace {

// The 256-entry table lives in 16 registers; each of 8 two-register permutes looks up 32 of its
// entries by the low 5 bits of the code, and bits 5-7 pick among them with three blends. About
// twice the speed of a gather here.
__attribute__((target("avx512f"))) void lutAvx512(const std::uint8_t* src, const float* lut,
                                                  float* dst, std::size_t n) {
  __m512 t[16];
  for (int k = 0; k < 16; ++k) t[k] = _mm512_loadu_ps(lut + 16 * k);
  std::size_t i = 0;
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
  for (; i < n; ++i) dst[i] = lut[src[i]];
}

}  // namespace

void lutToFloat(const std::uint8_t* src, const float* lut, float* dst, std::size_t n) {
  if (haveAvx512()) {
    lutAvx512(src, lut, dst, n);
    return;
  }
  for (std::size_t i = 0; i < n; ++i) dst[i] = lut[src[i]];
}

bool haveAvx512() {
  static const bool yes = __builtin_cpu_supports("avx512f");
  return yes;
}

namespace {

// Coefficient k takes row factor kRowOf[k] times column sum kColOf[k] (see sh.cpp).
constexpr int kRowOf[9] = {0, 2, 1, 2, 4, 3, 5, 3, 4};
constexpr int kColOf[9] = {0, 2, 0, 1, 4, 2, 0, 1, 3};
constexpr int kFlushRows = 64;  // float lanes hold at most this many rows before going to double

// Portable: column sums of one row, s[k*3 + c] in RGB order.
void rowSumsGeneric(const float* row, RowOrder order, const EquirectTables& t, float* s) {
  float a[5][3] = {};
  const float *c0 = t.col[0].data(), *c1 = t.col[1].data(), *c2 = t.col[2].data(),
              *c3 = t.col[3].data(), *c4 = t.col[4].data();
  for (int j = 0; j < t.width; ++j) {
    const float x = row[3 * j], y = row[3 * j + 1], z = row[3 * j + 2];
    a[0][0] += c0[j] * x, a[0][1] += c0[j] * y, a[0][2] += c0[j] * z;
    a[1][0] += c1[j] * x, a[1][1] += c1[j] * y, a[1][2] += c1[j] * z;
    a[2][0] += c2[j] * x, a[2][1] += c2[j] * y, a[2][2] += c2[j] * z;
    a[3][0] += c3[j] * x, a[3][1] += c3[j] * y, a[3][2] += c3[j] * z;
    a[4][0] += c4[j] * x, a[4][1] += c4[j] * y, a[4][2] += c4[j] * z;
  }
  const bool bgr = order == RowOrder::Bgr;
  for (int k = 0; k < 5; ++k) {
    s[3 * k + 0] = bgr ? a[k][2] : a[k][0];
    s[3 * k + 1] = a[k][1];
    s[3 * k + 2] = bgr ? a[k][0] : a[k][2];
  }
}

// 16 interleaved pixels (48 floats) to three planes.
__attribute__((target("avx512f"))) inline void deinterleave(__m512 v0, __m512 v1, __m512 v2,
                                                            __m512& a, __m512& b, __m512& c) {
  const __m512i a1 = _mm512_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21, 24, 27, 30, 0, 0, 0, 0, 0);
  const __m512i a2 = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 17, 20, 23, 26, 29);
  const __m512i b1 = _mm512_setr_epi32(1, 4, 7, 10, 13, 16, 19, 22, 25, 28, 31, 0, 0, 0, 0, 0);
  const __m512i b2 = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 18, 21, 24, 27, 30);
  const __m512i c1 = _mm512_setr_epi32(2, 5, 8, 11, 14, 17, 20, 23, 26, 29, 0, 0, 0, 0, 0, 0);
  const __m512i c2 = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 16, 19, 22, 25, 28, 31);
  a = _mm512_permutex2var_ps(_mm512_permutex2var_ps(v0, a1, v1), a2, v2);
  b = _mm512_permutex2var_ps(_mm512_permutex2var_ps(v0, b1, v1), b2, v2);
  c = _mm512_permutex2var_ps(_mm512_permutex2var_ps(v0, c1, v1), c2, v2);
}

// Loads 16 pixels, or the last n < 16 with zeros after them.
__attribute__((target("avx512f"))) inline void loadPixels(const float* p, int n, __m512& a,
                                                          __m512& b, __m512& c) {
  if (n >= 16) {
    deinterleave(_mm512_loadu_ps(p), _mm512_loadu_ps(p + 16), _mm512_loadu_ps(p + 32), a, b, c);
    return;
  }
  const int f = 3 * n;
  const auto mask = [](int bits) {
    return __mmask16(bits >= 16 ? 0xFFFF : bits <= 0 ? 0 : (1u << bits) - 1);
  };
  deinterleave(_mm512_maskz_loadu_ps(mask(f), p), _mm512_maskz_loadu_ps(mask(f - 16), p + 16),
               _mm512_maskz_loadu_ps(mask(f - 32), p + 32), a, b, c);
}

// s[k][c] += col[k][j..j+15] * (x, y, z)[c].
__attribute__((target("avx512f"), always_inline)) inline void accumulate(__m512 (&s)[5][3],
                                                                         const float* const* col,
                                                                         int j, __m512 x, __m512 y,
                                                                         __m512 z) {
  for (int k = 0; k < 5; ++k) {
    __m512 wk = _mm512_loadu_ps(col[k] + j);
    asm("" : "+v"(wk));  // keep the weight in a register: folding it into 3 FMAs triples loads
    s[k][0] = _mm512_fmadd_ps(wk, x, s[k][0]);
    s[k][1] = _mm512_fmadd_ps(wk, y, s[k][1]);
    s[k][2] = _mm512_fmadd_ps(wk, z, s[k][2]);
  }
}

// lane[c] += factor * (r, g, b)[c] for one coefficient's three channel accumulators.
__attribute__((target("avx512f"), always_inline)) inline void addCoefficient(float* lane,
                                                                             float factor, __m512 r,
                                                                             __m512 g, __m512 b) {
  const __m512 f = _mm512_set1_ps(factor);
  _mm512_store_ps(lane, _mm512_fmadd_ps(f, r, _mm512_load_ps(lane)));
  _mm512_store_ps(lane + 16, _mm512_fmadd_ps(f, g, _mm512_load_ps(lane + 16)));
  _mm512_store_ps(lane + 32, _mm512_fmadd_ps(f, b, _mm512_load_ps(lane + 32)));
}

// One row: 15 column sums as 16-lane vectors, then acc[k][c] += rowFactor[k] * s[col(k)][c].
__attribute__((target("avx512f"))) void addRowAvx512(const float* row, RowOrder order,
                                                     const EquirectTables& t, int i,
                                                     float* accLanes) {
  __m512 s[5][3];
  for (auto& a : s)
    for (auto& v : a) v = _mm512_setzero_ps();
  const int w = t.width;
  const float* col[5] = {t.col[0].data(), t.col[1].data(), t.col[2].data(), t.col[3].data(),
                         t.col[4].data()};
  int j = 0;
  const int full = w & ~15;
  if (w >= 1024) {  // large rows stream from RAM: prefetch ahead
    for (; j < full; j += 16) {
      const char* ahead = reinterpret_cast<const char*>(row + 3 * j + 1536);  // 6 KB ahead, 3 lines
      _mm_prefetch(ahead, _MM_HINT_T0);
      _mm_prefetch(ahead + 64, _MM_HINT_T0);
      _mm_prefetch(ahead + 128, _MM_HINT_T0);
      __m512 x, y, z;
      deinterleave(_mm512_loadu_ps(row + 3 * j), _mm512_loadu_ps(row + 3 * j + 16),
                   _mm512_loadu_ps(row + 3 * j + 32), x, y, z);
      accumulate(s, col, j, x, y, z);
    }
  } else {
    for (; j < full; j += 16) {
      __m512 x, y, z;
      deinterleave(_mm512_loadu_ps(row + 3 * j), _mm512_loadu_ps(row + 3 * j + 16),
                   _mm512_loadu_ps(row + 3 * j + 32), x, y, z);
      accumulate(s, col, j, x, y, z);
    }
  }
  if (j < w) {
    __m512 x, y, z;
    loadPixels(row + 3 * j, w - j, x, y, z);
    accumulate(s, col, j, x, y, z);
  }
  // acc[k][c] += rowFactor[row(k)] * s[col(k)][c], written out with constant indices: indexing
  // s by a table value would force the 15 row sums out of registers for the whole row loop.
  const bool bgr = order == RowOrder::Bgr;
#define LP_ADD(k, r, col)                                                                  \
  addCoefficient(accLanes + 48 * (k), t.row[r][i], bgr ? s[col][2] : s[col][0], s[col][1], \
                 bgr ? s[col][0] : s[col][2])
  LP_ADD(0, 0, 0);  // L00  = k0 R1 S1
  LP_ADD(1, 2, 2);  // L1-1 = k1 Rs Ssin
  LP_ADD(2, 1, 0);  // L10  = k1 Rc S1
  LP_ADD(3, 2, 1);  // L11  = k1 Rs Scos
  LP_ADD(4, 4, 4);  // L2-2 = k4 Rs2 Ssin2
  LP_ADD(5, 3, 2);  // L2-1 = k2 Rsc Ssin
  LP_ADD(6, 5, 0);  // L20  = k3 R3 S1
  LP_ADD(7, 3, 1);  // L21  = k2 Rsc Scos
  LP_ADD(8, 4, 3);  // L22  = k4 Rs2 Scos2
#undef LP_ADD
}

// Nine weights times three channels is 27 accumulators: with the pixels and the deinterleave
// indices that overflows the 32 vector registers, so each block of pixels is swept twice, for
// coefficients 0-4 and 5-8 (the second sweep reads the block from L1).
// Nine weights times three channels is 27 accumulators: with the pixels and the deinterleave
// indices that overflows the 32 vector registers, so each run of pixels is swept twice, for
// coefficients 0-4 and 5-8 (the second sweep reads the pixels from L1).
// acc[k][c] += w_k * (x, y, z)[c] for kN weights at w, 16 apart.
template <int kN>
__attribute__((target("avx512f"), always_inline)) inline void weightedStep(__m512 (&acc)[kN][3],
                                                                           const float* w, __m512 x,
                                                                           __m512 y, __m512 z) {
  for (int k = 0; k < kN; ++k) {
    __m512 wk = _mm512_loadu_ps(w + 16 * k);
    asm("" : "+v"(wk));
    acc[k][0] = _mm512_fmadd_ps(wk, x, acc[k][0]);
    acc[k][1] = _mm512_fmadd_ps(wk, y, acc[k][1]);
    acc[k][2] = _mm512_fmadd_ps(wk, z, acc[k][2]);
  }
}

template <int K0, int K1>
__attribute__((target("avx512f"))) inline void weightedSweep(const float* rgb, std::size_t b0,
                                                             std::size_t b1, const float* blocked,
                                                             double* out) {
  constexpr int kN = K1 - K0;
  __m512 acc[kN][3];
  for (auto& a : acc)
    for (auto& v : a) v = _mm512_setzero_ps();
  // Full blocks without masks (a branch inside this loop made GCC keep the accumulators in
  // memory), then the tail.
  std::size_t i = b0;
  for (; i + 16 <= b1; i += 16) {
    __m512 x, y, z;
    deinterleave(_mm512_loadu_ps(rgb + 3 * i), _mm512_loadu_ps(rgb + 3 * i + 16),
                 _mm512_loadu_ps(rgb + 3 * i + 32), x, y, z);
    weightedStep<kN>(acc, blocked + (i / 16) * 9 * 16 + K0 * 16, x, y,
                     z);  // zero-padded past the end
  }
  if (i < b1) {
    __m512 x, y, z;
    loadPixels(rgb + 3 * i, int(b1 - i), x, y, z);
    weightedStep<kN>(acc, blocked + (i / 16) * 9 * 16 + K0 * 16, x, y,
                     z);  // zero-padded past the end
  }
  for (int k = 0; k < kN; ++k)
    for (int c = 0; c < 3; ++c) out[3 * (K0 + k) + c] += _mm512_reduce_add_ps(acc[k][c]);
}

__attribute__((target("avx512f"))) void weightedSumsAvx512(const float* rgb, std::size_t n,
                                                           const float* blocked, double* out) {
  constexpr std::size_t kRun = 1024;  // 12 KB of pixels: stays in L1 for the second sweep
  for (std::size_t b0 = 0; b0 < n; b0 += kRun) {
    const std::size_t b1 = std::min(n, b0 + kRun);
    weightedSweep<0, 5>(rgb, b0, b1, blocked, out);
    weightedSweep<5, 9>(rgb, b0, b1, blocked, out);
  }
}

}  // namespace

EquirectAccumulator::EquirectAccumulator(const EquirectTables& t) : t_(t), avx512_(haveAvx512()) {
  std::fill(std::begin(acc_), std::end(acc_), 0.0f);
}

void EquirectAccumulator::addRow(const float* row, RowOrder order, int i) {
  if (avx512_) {
    addRowAvx512(row, order, t_, i, acc_);
  } else {
    float s[15];
    rowSumsGeneric(row, order, t_, s);
    for (int k = 0; k < 9; ++k)
      for (int c = 0; c < 3; ++c)
        acc_[(3 * k + c) * 16] += t_.row[kRowOf[k]][i] * s[3 * kColOf[k] + c];
  }
  if (++pending_ == kFlushRows) flush(nullptr);  // float lanes -> double totals
}

void EquirectAccumulator::flush(double* out) {
  for (int q = 0; q < 27; ++q) {
    double sum = 0;
    for (int l = 0; l < 16; ++l) sum += acc_[q * 16 + l];
    totals_[q] += sum;
  }
  std::fill(std::begin(acc_), std::end(acc_), 0.0f);
  pending_ = 0;
  if (out) {
    for (int q = 0; q < 27; ++q) out[q] += totals_[q];
    std::fill(std::begin(totals_), std::end(totals_), 0.0);
  }
}

namespace {

__attribute__((target("f16c,avx"))) void halfToFloatF16c(const std::uint16_t* src, float* dst,
                                                         std::size_t n) {
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8)
    _mm256_storeu_ps(dst + i,
                     _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(src + i))));
  for (; i < n; ++i) dst[i] = _cvtsh_ss(src[i]);
}

float halfToFloatScalar(std::uint16_t h) {
  const std::uint32_t sign = std::uint32_t(h & 0x8000) << 16, exp = (h >> 10) & 0x1F,
                      man = h & 0x3FF;
  std::uint32_t bits;
  if (exp == 0) {
    if (man == 0) {
      bits = sign;
    } else {  // subnormal: renormalise
      int e = -1;
      std::uint32_t m = man;
      do {
        ++e;
        m <<= 1;
      } while (!(m & 0x400));
      bits = sign | std::uint32_t(127 - 15 - e) << 23 | (m & 0x3FF) << 13;
    }
  } else if (exp == 31) {
    bits = sign | 0x7F800000u | man << 13;
  } else {
    bits = sign | (exp + 127 - 15) << 23 | man << 13;
  }
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

}  // namespace

void halfToFloat(const std::uint16_t* src, float* dst, std::size_t n) {
  static const bool f16c = __builtin_cpu_supports("f16c");
  if (f16c) {
    halfToFloatF16c(src, dst, n);
    return;
  }
  for (std::size_t i = 0; i < n; ++i) dst[i] = halfToFloatScalar(src[i]);
}

void weightedSums(const float* rgb, std::size_t n, const float* blocked, double* out) {
  if (haveAvx512()) {
    weightedSumsAvx512(rgb, n, blocked, out);
    return;
  }
  constexpr std::size_t kBlock = 4096;
  for (std::size_t b0 = 0; b0 < n; b0 += kBlock) {
    const std::size_t b1 = std::min(n, b0 + kBlock);
    float acc[27] = {};
    for (std::size_t i = b0; i < b1; ++i) {
      const float x = rgb[3 * i], y = rgb[3 * i + 1], z = rgb[3 * i + 2];
      const float* w = blocked + (i / 16) * 9 * 16 + i % 16;
      for (int k = 0; k < 9; ++k) {
        const float wk = w[16 * k];
        acc[3 * k] += wk * x, acc[3 * k + 1] += wk * y, acc[3 * k + 2] += wk * z;
      }
    }
    for (int q = 0; q < 27; ++q) out[q] += acc[q];
  }
}

}  // namespace lp::kernel
