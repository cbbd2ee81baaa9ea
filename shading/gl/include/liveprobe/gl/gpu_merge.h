#pragma once
// The bracket merge's pixel loop on the GPU (lp::merge::FrameKernel, liveprobe/hdr/merge_frame.h):
// the frames' 8-bit codes uploaded as they are, decoded through the camera's response in the
// shader, each pixel judged as the CPU's row kernel judges it (the same weights, the same
// contradictions, the same confidence sums), and the merged radiance weighed by the equirect
// column integrals in the same pass: one workgroup a row, each row's sums read back. The
// luminance the next merge reads stays on the GPU (read back where the merge asks:
// FrameInput::luminanceBack, readLuminance); the merged frame comes back where it is asked for
// (FrameInput::rgb), or stays on the GPU for a context that shares this one's objects to draw
// (FrameInput::rgbKept, takeKeptImage: liveprobe/gl/gpu_image.h).
// Needs a current context with compute shaders (GL 4.3; hasCompute()).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "liveprobe/gl/gpu_image.h"
#include "liveprobe/gl/handles.h"
#include "liveprobe/hdr/merge_frame.h"

namespace lp::gl {

/// How the merge's pass is laid out: the defaults are what every command runs; the rest is
/// for measuring (liveprobe-gpu-bench's sweeps).
struct GpuMergeShape {
  /// The workgroups a row is merged in; one is fastest (each workgroup's fixed cost, the
  /// response's load and the sums' reduction, outweighs the parallelism: the sweep on an H200).
  int rowParts = 1;
  int groupSize = 128;  ///< invocations a workgroup: a power of two from 32 to 1024
  /// false: a bound, not the CPU's merge: every reading kept at its hat weight, no contradiction
  /// judged, to time what the judgement costs.
  bool judge = true;
};

class GpuMerge {
 public:
  /// Throws ContextError where the context has no compute shaders, or `shape` is not one.
  explicit GpuMerge(const GpuMergeShape& shape = {});
  ~GpuMerge();
  GpuMerge(const GpuMerge&) = delete;
  GpuMerge& operator=(const GpuMerge&) = delete;

  /// One merge (what lp::BracketMerger::setFrameKernel takes). A frame kept from an earlier
  /// merge (merge::FrameInput::key) is not uploaded again: a still camera's bracket uploads one
  /// frame a merge.
  void operator()(const merge::FrameInput& in, std::vector<merge::RowSums>& rows);
  /// The luminance of the merge whose FrameInput::luminanceKey was `key`, read into `into`
  /// (what lp::BracketMerger::setFrameKernel's `fetch` takes); false where no buffer holds it.
  /// The last merge's and the one before it are always held.
  bool readLuminance(std::uint64_t key, float* into);
  /// The last merge's frame where it was kept (FrameInput::rgbKept), handed over once; none
  /// where it was not kept, or was taken.
  std::shared_ptr<const GpuImage> takeKeptImage() { return std::move(kept_); }
  /// Buffers made for kept frames: those a reader held when a merge wrote one, plus one.
  std::size_t keptBuffers() const { return keptPool_.buffers(); }
  /// Frames uploaded so far.
  std::size_t framesUploaded() const { return uploaded_; }
  /// Luminance buffers (the last merges') uploaded so far: the first merge's two, then only
  /// those the camera's turn changed (merge::FrameInput::previousKey).
  std::size_t luminanceUploaded() const { return luminanceUploaded_; }

 private:
  /// N places (frame slots, luminance buffers), each holding what went in under a key (0: none,
  /// or nothing to find again), and which of them one merge has taken.
  template <int N>
  struct Keyed {
    std::uint64_t key[N] = {};
    bool taken[N] = {};
    void startMerge() { std::fill(std::begin(taken), std::end(taken), false); }
    void forget() { std::fill(std::begin(key), std::end(key), 0); }
    /// The place holding `k` (not `0`) whatever this merge took; -1 where none does.
    int holding(std::uint64_t k) const {
      for (int i = 0; k != 0 && i < N; ++i)
        if (key[i] == k) return i;
      return -1;
    }
    /// The place still holding `k` (not `0`), now taken; -1 where none does.
    int find(std::uint64_t k) {
      for (int i = 0; k != 0 && i < N; ++i)
        if (key[i] == k && !taken[i]) return taken[i] = true, i;
      return -1;
    }
    /// A place this merge has not taken, now holding `k`.
    int claim(std::uint64_t k) {
      const int i = int(std::find(std::begin(taken), std::end(taken), false) - std::begin(taken));
      taken[i] = true, key[i] = k;
      return i;
    }
  };
  /// `buffer` holding `bytes` from `data` (grown where it is smaller), bound at `binding`.
  void fill(int binding, const void* data, std::size_t bytes);
  /// The last merges' luminance and this merge's bound (kept ones by key, the rest uploaded);
  /// which of luminance_ this merge writes.
  int bindLuminance(const merge::FrameInput& in, std::size_t pixels);
  /// Frame `frame` of `in` turned from the slot at byte `source` into the one at `dest`.
  void turnFrame(const merge::FrameInput& in, int frame, GLuint source, GLuint dest);
  Program program_, turn_;
  Buffer buffers_[11];
  std::size_t sizes_[11] = {};
  Keyed<2 * merge::kMaxFrames> slots_;  ///< the window's frames, as taken and turned
  std::vector<std::uint8_t> recode_;    ///< the response's way back, as uploaded for the turn
  std::size_t slotStride_ = 0;          ///< the bytes of a slot
  std::size_t uploaded_ = 0;
  Buffer luminance_[3];     ///< the last merge's, the last trusted one's, this one's
  Keyed<3> luminanceKeys_;  ///< what each holds (merge::FrameInput::previousKey)
  std::size_t luminancePixels_ = 0, luminanceUploaded_ = 0;
  int rowParts_ = 1;
  GpuImagePool keptPool_;
  std::shared_ptr<const GpuImage> kept_;
};

}  // namespace lp::gl
