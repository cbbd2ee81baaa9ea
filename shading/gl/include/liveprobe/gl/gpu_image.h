#pragma once
// A frame kept on the GPU for another context to draw: the bracket the capture thread's context
// merged (gl::GpuMerge, FrameInput::rgbKept), drawn as the background by the viewer's context
// (Renderer::setBackground). The two contexts share objects (ContextSpec::shareWith); the image
// is a buffer of RGB floats, rows top to bottom. Fences order them (as the GL spec's shared
// objects ask): the drawing context waits on the GPU for the merge that wrote the buffer, and
// the merge that writes it next waits for the copy that read it. A buffer is written again only
// once no GpuImage of it is held. An image outlives its pool (the last frame of a stream is drawn
// after its merge ended): its buffer is then deleted by its first read, in the drawing context.
#include <cstddef>
#include <functional>
#include <memory>

#include "liveprobe/gl/gl.h"

namespace lp::gl {

class GpuImagePool;

class GpuImage {
 public:
  ~GpuImage();
  GpuImage(const GpuImage&) = delete;
  GpuImage& operator=(const GpuImage&) = delete;
  int width() const { return width_; }
  int height() const { return height_; }
  /// In the current context (one sharing with the maker's): waits on the GPU for the write,
  /// calls `copy` with the buffer, then fences what `copy` issued. Where the maker is gone (its
  /// GpuImagePool), the buffer is deleted after `copy`: a later read returns false, calling
  /// nothing (the copy it made is the image).
  bool read(const std::function<void(GLuint buffer)>& copy) const;

 private:
  friend class GpuImagePool;
  struct Places;
  GpuImage(std::shared_ptr<Places> places, int place, int width, int height);
  std::shared_ptr<Places> places_;
  int place_, width_, height_;
};

/// The maker's side: buffers reused once no image of them is held. Made, used and destroyed on
/// the maker's thread with its context current; images it handed out may outlive it.
class GpuImagePool {
 public:
  GpuImagePool();
  ~GpuImagePool();  ///< deletes the buffers no image holds (a held one: its image's read does)
  GpuImagePool(const GpuImagePool&) = delete;
  GpuImagePool& operator=(const GpuImagePool&) = delete;
  /// A buffer of at least `bytes` that no image holds, to write the next image into; the GPU
  /// waits (glWaitSync) for the last copy that read it before what follows.
  GLuint take(std::size_t bytes);
  /// The image written into the buffer take() gave, fenced after the commands issued so far.
  std::shared_ptr<const GpuImage> give(int width, int height);
  /// Buffers made so far (those held when one was taken, plus one).
  std::size_t buffers() const;

 private:
  std::shared_ptr<GpuImage::Places> places_;
  int taken_ = -1;
};

}  // namespace lp::gl
