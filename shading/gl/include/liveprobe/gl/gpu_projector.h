#pragma once
// The projection on the GPU: a frame uploaded as a texture in its own encoding (8-bit codes,
// half or float), through pixel-buffer objects the caller writes into, and a compute pass that
// reduces it to the nine radiance coefficients with the same weights as lp::Projector
// (liveprobe/sh/projector.h): the exact equirect pixel integrals, or the other layouts' per-pixel
// Y_lm dw, and 8-bit codes decoded through the same 256-entry table. Per-workgroup partial sums
// in fp32, then a second pass to the 27 sums. Needs a current context with compute shaders
// (GL 4.3); hasCompute() says whether it has them.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "liveprobe/gl/handles.h"
#include "liveprobe/sh/projector.h"

namespace lp::gl {

/// Whether the current context runs compute shaders (GL 4.3 or later).
bool hasCompute();

/// A frame's pixels on the GPU, as a texture of the frame's size and format (RgbF32: RGB32F,
/// RgbF16: RGB16F, 8-bit: RGB8 holding the codes, in the frame's channel order). Frames come in
/// through two pixel-buffer objects in turn: the caller writes the next frame into one (map())
/// while the other's transfer runs; commit() queues the transfer and returns at once. With
/// ARB_buffer_storage (GL 4.4) the buffers stay mapped (persistent, coherent); without it each
/// is mapped per frame.
class FrameTexture {
 public:
  FrameTexture() = default;
  /// Where the next frame's pixels go: width * height * bytes per pixel, rows top to bottom,
  /// packed. Waits only if the GPU still reads the buffer from two frames ago.
  void* map(PanoramaFormat format, int width, int height);
  /// Ends the write and queues the transfer into the texture.
  void commit();
  /// map(), a copy of `frame`'s rows, commit(): for frames already in memory.
  void upload(const PanoramaView& frame);

  GLuint texture() const { return texture_.get(); }
  PanoramaFormat format() const { return format_; }
  int width() const { return width_; }
  int height() const { return height_; }
  std::size_t frameBytes() const;
  bool persistent() const { return persistent_; }

 private:
  void allocate(PanoramaFormat format, int width, int height);
  Texture texture_;
  std::array<Buffer, 2> pbo_;
  std::array<void*, 2> mapped_{};
  std::array<GLsync, 2> fence_{};
  int next_ = 0;
  bool writing_ = false, persistent_ = false;
  PanoramaFormat format_ = PanoramaFormat::RgbF32;
  int width_ = 0, height_ = 0;
};

/// The compute passes for one (layout, size). dispatch() queues a frame's projection and
/// returns at once; read() hands back the coefficients of the oldest frame not yet read, one
/// frame later without waiting, or at once with `wait`.
class GpuProjector {
 public:
  /// Throws ContextError where the context has no compute shaders, lp::Error where the frame
  /// size does not fit the layout. `rowsPerGroup`: the rows each invocation of the first pass
  /// sums (0 picks: about 768 groups, 16 to 256 rows; liveprobe-gpu-bench measures the choice).
  GpuProjector(const LayoutSpec& spec, int width, int height, int rowsPerGroup = 0);
  /// The same, from the CPU's projector of the layout and size (its tables, not made again).
  explicit GpuProjector(const Projector& tables, int rowsPerGroup = 0);
  ~GpuProjector();

  /// Queues the projection of `frame` (this projector's size). `decode`: the 256-entry table of
  /// an 8-bit frame (code -> linear radiance), as lp::PanoramaView holds it; `bgr`: the
  /// frame's channels are B, G, R (the sums are swapped back as the CPU does).
  void dispatch(const FrameTexture& frame, const float* decode = nullptr, bool bgr = false);
  /// The coefficients of the oldest dispatched frame not read yet: nullopt when none is
  /// pending, or when it is not finished and `wait` is false.
  std::optional<Sh9> read(bool wait);
  /// dispatch() and read(true): one frame, waited for.
  Sh9 project(const FrameTexture& frame, const float* decode = nullptr, bool bgr = false);
  /// Each row's largest linear channel value (8-bit codes through `decode`), as
  /// lp::Projector::project's rowPeaks: what the light search starts from. A pass of one
  /// workgroup a row, read back at once (height floats).
  std::vector<float> rowPeaks(const FrameTexture& frame, const float* decode = nullptr);
  /// Frames dispatched and not read.
  int pending() const { return pending_; }
  /// Workgroups of the first pass (each writes 27 partial sums).
  int groups() const { return groupsX_ * groupsY_; }
  /// The rows each of them sums.
  int rowsPerGroup() const { return rowsPerGroup_; }

 private:
  void setDecode(const FrameTexture& frame, const float* decode);
  struct Slot {
    Buffer result;
    GLsync fence = nullptr;
    bool bgr = false;
  };
  LayoutSpec spec_;
  int width_, height_;
  Program reduce_, finish_, peaks_;
  Buffer rows_, cols_, weights_, decode_, partial_, rowPeaks_;
  std::array<Slot, 2> slots_;
  int groupsX_ = 0, groupsY_ = 0, rowsPerGroup_ = 0;
  int head_ = 0, pending_ = 0;
  std::array<float, 256> lastDecode_{};
  bool decodeSet_ = false;
};

/// A frame path's frames projected on the GPU, in the context current where it is called: each
/// frame uploaded as the projection reads it, projected and read back (with the row peaks where
/// lights are searched); the passes made again whenever the job's tables are. What
/// lp::FrameRequest::projectWith calls.
class GpuFrameProjection {
 public:
  Sh9 operator()(const ProjectionJob& job);

 private:
  FrameTexture frame_;
  std::unique_ptr<GpuProjector> projector_;
  std::uint64_t tablesId_ = 0;
};

}  // namespace lp::gl
