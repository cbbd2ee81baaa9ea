#include "liveprobe/gl/gpu_image.h"

#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "liveprobe/gl/context.h"

namespace lp::gl {

/// The buffers, shared by the pool and its images; the mutex orders the maker's thread and the
/// drawing one.
struct GpuImage::Places {
  struct Place {
    GLuint buffer = 0;
    std::size_t bytes = 0;
    GLsync written = nullptr, read = nullptr;
    bool held = false;     ///< by the pool (taken) or by an image
    bool deleted = false;  ///< the pool gone, read by its image once (or never held)
  };
  std::mutex mutex;
  bool alive = true;
  std::vector<Place> places;
};

namespace {
void dropFence(GLsync& s) {
  if (s) glDeleteSync(s);
  s = nullptr;
}
}  // namespace

GpuImage::GpuImage(std::shared_ptr<Places> places, int place, int width, int height)
    : places_(std::move(places)), place_(place), width_(width), height_(height) {}

GpuImage::~GpuImage() {
  std::lock_guard lock(places_->mutex);
  // (Once the pool is gone, a buffer never read goes with the share group: deleting it here
  // would need a context of that group current, which the dropping thread may not have.)
  places_->places[std::size_t(place_)].held = false;
}

bool GpuImage::read(const std::function<void(GLuint buffer)>& copy) const {
  std::lock_guard lock(places_->mutex);
  Places::Place& p = places_->places[std::size_t(place_)];
  if (p.deleted) return false;
  if (p.written) glWaitSync(p.written, 0, GL_TIMEOUT_IGNORED);
  copy(p.buffer);
  dropFence(p.read);
  if (!places_->alive) {
    // The last read: nothing writes the buffer again. GL deletes it once the copy is done.
    dropFence(p.written);
    glDeleteBuffers(1, &p.buffer);
    p.deleted = true;
    return true;
  }
  p.read = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  glFlush();  // (a fence another context waits on must reach the GPU)
  return true;
}

GpuImagePool::GpuImagePool() : places_(std::make_shared<GpuImage::Places>()) {}

GpuImagePool::~GpuImagePool() {
  std::lock_guard lock(places_->mutex);
  places_->alive = false;
  for (auto& p : places_->places) {
    dropFence(p.read);
    if (p.held) continue;  // an image's: its read deletes it (the written fence too)
    dropFence(p.written);
    glDeleteBuffers(1, &p.buffer);
    p.deleted = true;
  }
  glFlush();  // (the held images' written fences must reach the GPU before this context goes)
}

GLuint GpuImagePool::take(std::size_t bytes) {
  std::lock_guard lock(places_->mutex);
  auto& all = places_->places;
  std::size_t i = 0;
  while (i < all.size() && all[i].held) ++i;
  if (i == all.size()) {
    all.emplace_back();
    glGenBuffers(1, &all[i].buffer);
  }
  auto& p = all[i];
  p.held = true, taken_ = int(i);
  if (p.read) glWaitSync(p.read, 0, GL_TIMEOUT_IGNORED);
  dropFence(p.read), dropFence(p.written);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, p.buffer);
  if (p.bytes != bytes) {
    while (glGetError() != GL_NO_ERROR) {
    }
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(bytes), nullptr, GL_DYNAMIC_COPY);
    if (glGetError() == GL_OUT_OF_MEMORY)
      throw ContextError("a frame kept on the GPU: out of GPU memory for " +
                         std::to_string(bytes >> 20) + " MB");
    p.bytes = bytes;
  }
  return p.buffer;
}

std::shared_ptr<const GpuImage> GpuImagePool::give(int width, int height) {
  std::lock_guard lock(places_->mutex);
  auto& p = places_->places.at(std::size_t(taken_));
  p.written = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  glFlush();
  // (The image holds the buffer from here: taken_'s hold passes to it.)
  return std::shared_ptr<const GpuImage>(
      new GpuImage(places_, std::exchange(taken_, -1), width, height));
}

std::size_t GpuImagePool::buffers() const {
  std::lock_guard lock(places_->mutex);
  return places_->places.size();
}

}  // namespace lp::gl
