#pragma once
// The projection kernels (private to shading_sh). Two implementations of each: AVX-512 (chosen at
// run time where the CPU has it) and portable C++ that the compiler vectorises. Both accumulate
// in float over at most one row (or 4096 pixels) and in double beyond, so a 4K frame stays
// within ~1e-7 of L00 of a float64 sum.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace lp::kernel {

/// Per-column integrals of 1, cos p, sin p, cos 2p, sin 2p, zero-padded to a multiple of 16, and
/// per-row integrals of the six t-factors (shading/src/sh.cpp derives them).
struct EquirectTables {
  int width = 0, height = 0;
  std::array<std::vector<float>, 5> col;
  std::array<std::vector<float>, 6> row;
};

/// How to read a row: packed RGB floats, or BGR floats (an 8-bit BGR row after its lookup table).
enum class RowOrder : std::uint8_t { Rgb, Bgr };

/// Adds the 27 radiance sums of rows [row0, row1) to out (k-major, RGB). `rowAt(i)` returns a
/// pointer to row i as 3 * width floats in `order`.
template <class RowAt>
void equirectRows(const EquirectTables& t, RowAt rowAt, RowOrder order, int row0, int row1,
                  double* out);

/// Sum over n pixels of rgb[i] * w_k[i] for the nine weights; adds to out (k-major, RGB).
/// `blocked` holds the weights in blocks of 16 pixels: w_k of pixel 16 b + l is at
/// blocked[(9 b + k) * 16 + l] (one sequential stream, which the prefetchers follow; nine
/// separate planes are nine streams). n is a multiple of 16 except for the last call.
void weightedSums(const float* rgb, std::size_t n, const float* blocked, double* out);

bool haveAvx512();

/// dst[i] = lut[src[i]] (a 256-entry table; AVX-512 register permutes where available).
void lutToFloat(const std::uint8_t* src, const float* lut, float* dst, std::size_t n);

/// IEEE binary16 to float (F16C where the CPU has it).
void halfToFloat(const std::uint16_t* src, float* dst, std::size_t n);

// Implementation detail of equirectRows: one row's 15 column-weighted sums (s[k*3 + c]) are
// combined with the row factors into 27 lanes of accumulators. Exposed for the template.
struct EquirectAccumulator {
  explicit EquirectAccumulator(const EquirectTables& t);
  void addRow(const float* row, RowOrder order, int i);
  /// Moves the float lanes into the double totals; with `out`, adds the totals there and resets.
  void flush(double* out);

 private:
  const EquirectTables& t_;
  alignas(64) float acc_[27 * 16];
  double totals_[27] = {};
  int pending_ = 0;
  bool avx512_;
};

template <class RowAt>
void equirectRows(const EquirectTables& t, RowAt rowAt, RowOrder order, int row0, int row1,
                  double* out) {
  EquirectAccumulator acc(t);
  for (int i = row0; i < row1; ++i) acc.addRow(rowAt(i), order, i);
  acc.flush(out);
}

}  // namespace lp::kernel
