#pragma once
// Projection of whole panoramas to radiance coefficients: a non-owning view of a frame in any
// pixel format and layout, and a Projector that precomputes what one (layout, size) needs.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "liveprobe/sh/executor.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/sh.h"

namespace lp {

/// How a panorama's pixels are stored: three channels per pixel, rows top to bottom.
enum class PanoramaFormat : std::uint8_t {
  RgbF32,  ///< linear radiance, float
  RgbF16,  ///< linear radiance, IEEE binary16
  BgrU8,   ///< 8-bit code values in OpenCV's order, decoded through a 256-entry table
  RgbU8,   ///< 8-bit code values, decoded through a 256-entry table
};

/// A panorama in memory, not owned: the data, its pixel format, row stride, size and layout.
struct PanoramaView {
  const void* data = nullptr;
  PanoramaFormat format = PanoramaFormat::RgbF32;
  int width = 0, height = 0;
  std::size_t rowStride = 0;  ///< bytes from one row to the next; 0 = packed
  LayoutSpec layout;
  /// 8-bit formats: code value -> linear radiance (256 floats, the exposure folded in).
  const float* decode = nullptr;

  static PanoramaView rgbF32(const float* rgb, int w, int h, LayoutSpec layout = {}) {
    return {rgb, PanoramaFormat::RgbF32, w, h, 0, layout, nullptr};
  }
  static PanoramaView rgbF16(const std::uint16_t* rgb, int w, int h, LayoutSpec layout = {}) {
    return {rgb, PanoramaFormat::RgbF16, w, h, 0, layout, nullptr};
  }
  static PanoramaView bgrU8(const std::uint8_t* bgr, int w, int h, const float* decode,
                            LayoutSpec layout = {}) {
    return {bgr, PanoramaFormat::BgrU8, w, h, 0, layout, decode};
  }
  std::size_t bytesPerPixel() const;
  /// rowStride, or the packed row size when it is 0.
  std::size_t strideBytes() const { return rowStride ? rowStride : bytesPerPixel() * width; }
};

/// The equirect projection's exact pixel integrals, what Projector weighs pixels with: pixel
/// (i, j) adds value * row[kRowOf[k]][i] * col[kColOf[k]][j] to coefficient k.
///   col: per column the integrals of 1, cos p, sin p, cos 2p, sin 2p, zero-padded to a
///        multiple of 16;
///   row: per row the integrals of the six t-factors with the basis constants folded in
///        (projector.cpp derives them).
struct EquirectIntegrals {
  int width = 0, height = 0;
  std::array<std::vector<float>, 5> col;
  std::array<std::vector<float>, 6> row;
  static constexpr int kRowOf[9] = {0, 2, 1, 2, 4, 3, 5, 3, 4};
  static constexpr int kColOf[9] = {0, 2, 0, 1, 4, 2, 0, 1, 3};
  /// Adds row y's part to the nine sums, from its five column-weighted sums (per channel).
  template <class Vec3>
  void addRow(std::size_t y, const Vec3 (&colSums)[5],
              std::array<glm::dvec3, kShCount>& sums) const {
    for (int k = 0; k < kShCount; ++k)
      sums[std::size_t(k)] += glm::dvec3(colSums[kColOf[k]]) * double(row[kRowOf[k]][y]);
  }
};

/// Projects frames of one (layout, size) to radiance coefficients L_lm (liveprobe/sh/sh.h). The
/// per-pixel directions and solid angles (for equirect, the exact separable row and column
/// integrals of the basis) are computed once here and reused for every frame.
///   - equirect: 15 multiply-adds per pair of pixels half a turn apart (five column-weighted
///     sums per channel; the pair shares its column integrals up to sign), combined with the
///     row integrals once per row; exact for radiance constant over each pixel.
///   - other layouts: Y_lm(dir) dw made per pixel from sqrt(dw) and sqrt(dw) dir (16 bytes a
///     pixel, read beside the frame), 30 multiply-adds; what the frame does not see is filled by
///     the layout's UnseenRule, linear in the pixels: the ground from one more sum (the pixels'
///     cosines to the up), the rest through extra weights of the edge's pixels.
/// Sums run in float over at most a row (or 4096 pixels) and in double beyond, so a 4K frame
/// keeps ~1e-7 of L00. The kernels are SIMD (liveprobe/sh/simd.h picks the instruction set).
class Projector {
 public:
  /// Throws lp::Error if the frame size does not fit the layout.
  Projector(const LayoutSpec& spec, int width, int height);
  ~Projector();
  Projector(Projector&&) noexcept;
  Projector& operator=(Projector&&) noexcept;

  const LayoutSpec& spec() const { return spec_; }
  int width() const { return width_; }
  int height() const { return height_; }
  /// The per-pixel samples (directions and solid angles), row-major.
  const std::vector<SphereSample>& samples() const { return samples_; }
  /// The share of the sphere the frame measures: exactly 1 for the panoramic layouts, less for
  /// a lens, whose rest spec().unseen fills in every projection.
  double coverage() const { return coverage_; }

  /// Radiance coefficients of `frame`, which must have this projector's size and layout (throws
  /// lp::Error otherwise, and for an 8-bit view without its decode table). With an executor the
  /// frame is split across its threads.
  /// `rowPeaks`, when given, receives per row the largest linear channel value of the row (what
  /// light extraction starts from, liveprobe/sh/lights.h). For equirect frames it is taken from
  /// each row while the projection holds it in cache; other layouts read the frame once more.
  Sh9 project(const PanoramaView& frame, Executor* executor = nullptr,
              std::vector<float>* rowPeaks = nullptr) const;

  /// The equirect layout's pixel integrals; nullptr for the other layouts.
  const EquirectIntegrals* equirectIntegrals() const;
  /// The other layouts' weights Y_lm(dir) dw with the fill's, in blocks of 16 pixels: weight k of
  /// pixel p at [((p / 16) * 9 + k) * 16 + p % 16], zero-padded to a whole block (what a GPU
  /// uploads; made when first asked); empty for equirect.
  const std::vector<float>& blockedWeights() const;

  /// Adds to `sums` (per coefficient, R G B in double) the coefficients of `values`, radiance
  /// given to the `count` pixels of row `row` from column `col` on, with the weights
  /// project() counts them with: for equirect the exact pixel integrals of the basis (the row's
  /// factor times the column sums), for other layouts Y_lm(dir) dw. So the coefficients of a
  /// change to a few pixels are exactly those project() would see.
  void addPixels(std::size_t row, std::size_t col, const Rgb* values, std::size_t count,
                 std::array<glm::dvec3, kShCount>& sums) const;

 private:
  struct Tables;
  void check(const PanoramaView& frame) const;
  /// The 27 sums (coefficient-major, then the frame's channel order).
  std::array<double, 27> equirectSums(const PanoramaView& frame, Executor* executor,
                                      std::vector<float>* rowPeaks) const;
  std::array<double, 27> sampleSums(const PanoramaView& frame, Executor* executor) const;
  /// A sample layout's nine weights of pixel p: Y_lm(dir) dw and its share of the fill.
  std::array<float, kShCount> pixelWeights(std::size_t p) const;
  LayoutSpec spec_;
  int width_, height_;
  std::vector<SphereSample> samples_;
  double coverage_ = 1.0;
  std::unique_ptr<const Tables> tables_;
};

/// Linear RGB of pixel `index` (row-major) of `frame`, in R, G, B order whatever the format.
Rgb readPixel(const PanoramaView& frame, std::size_t index);

/// The same for the `count` pixels of row `row` from column `col` on, into `out`.
void readPixels(const PanoramaView& frame, std::size_t row, std::size_t col, std::size_t count,
                Rgb* out);

/// One-off projection: Projector(frame.layout, frame.width, frame.height).project(frame).
Sh9 project(const PanoramaView& frame, Executor* executor = nullptr);

/// A frame for a projection elsewhere (the GPU's, liveprobe/gl/gpu_projector.h), as the frame path
/// hands it over (lp::FrameRequest::projectWith).
struct ProjectionJob {
  /// The frame as the projection reads it: an 8-bit frame with the lookup table that carries the
  /// photometry, a float frame as it is, a reduction's average.
  PanoramaView view;
  /// The CPU's projector of its layout and size: the weights to project with.
  const Projector& tables;
  /// Changes whenever the caller makes its tables again (another size, another layout).
  std::uint64_t tablesId = 0;
  /// Where lights are searched: to be filled with each row's largest value, as
  /// Projector::project's rowPeaks; nullptr otherwise.
  std::vector<float>* rowPeaks = nullptr;
  /// Where the projection says its own GPU time (ms, by timer queries read a few frames late:
  /// an earlier frame's), left empty where there is no GPU timer; nullptr: not asked.
  std::optional<double>* gpuMs = nullptr;
};

}  // namespace lp
