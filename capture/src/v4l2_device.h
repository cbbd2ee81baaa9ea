#pragma once
// What every V4L2 node liveprobe streams from (a camera's video node, its UVC metadata node)
// shares: the ioctl, retried when a signal interrupts it, and a buffer mapped from the driver,
// unmapped when it is destroyed (VIDIOC_QUERYBUF's length and offset; the kernel's
// "Streaming I/O (Memory Mapping)" page).
#include <linux/videodev2.h>

#include <cstddef>
#include <cstdint>
#include <string>

namespace lp {

/// open(2) of a V4L2 node, read-write and non-blocking (as the kernel's V4L2 open() page asks of
/// a streaming reader). Returns the descriptor; throws lp::Error naming `path` and what to do:
/// "no such device" (ENOENT), the video group for EACCES, "device busy" (EBUSY), else strerror.
int openV4l2Node(const std::string& path);

/// ioctl(2) on a V4L2 node, again while a signal interrupts it (EINTR).
int v4l2Ioctl(int fd, unsigned long request, void* arg);

class MappedBuffer {
 public:
  /// Maps buffer `b` of the node `fd`; valid() is false where mmap failed (errno says why).
  MappedBuffer(int fd, const v4l2_buffer& b);
  ~MappedBuffer();
  MappedBuffer(MappedBuffer&& o) noexcept;
  MappedBuffer& operator=(MappedBuffer&&) = delete;
  MappedBuffer(const MappedBuffer&) = delete;
  MappedBuffer& operator=(const MappedBuffer&) = delete;

  bool valid() const { return start_ != nullptr; }
  const std::uint8_t* data() const { return static_cast<const std::uint8_t*>(start_); }
  std::size_t length() const { return length_; }

 private:
  void* start_ = nullptr;
  std::size_t length_ = 0;
};

}  // namespace lp
