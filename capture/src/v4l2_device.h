#pragma once
// What every V4L2 node liveprobe streams from (a camera's video node, its UVC metadata node)
// shares: the ioctl, retried when a signal interrupts it, a buffer mapped from the driver,
// unmapped when it is destroyed, and the queue of those buffers a stream cycles through
// (written to the kernel's "Streaming I/O (Memory Mapping)" page).
#include <linux/videodev2.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

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

/// Throws lp::Error "NAME: WHAT: why", errno `err` said in words (ENODEV: the camera has gone).
[[noreturn]] void throwV4l2(const std::string& name, const std::string& what, int err);

/// The memory-mapped buffers of one streaming node for one buffer type (video or metadata
/// capture), RAII: made by VIDIOC_REQBUFS, VIDIOC_QUERYBUF and mmap; destroyed by
/// VIDIOC_STREAMOFF, munmap and VIDIOC_REQBUFS of 0 (each harmless on a node that has gone).
/// The descriptor stays its owner's and must outlive the queue. Every error is an lp::Error
/// beginning with `name` (the node's path).
class V4l2Queue {
 public:
  /// Asks for `count` buffers; fewer than `least` granted, or EBUSY (another program streams
  /// from the node), is refused in one line, the driver's buffers given back.
  V4l2Queue(int fd, v4l2_buf_type type, std::uint32_t count, std::uint32_t least, std::string name);
  ~V4l2Queue();
  V4l2Queue(const V4l2Queue&) = delete;
  V4l2Queue& operator=(const V4l2Queue&) = delete;

  /// Queues every buffer (VIDIOC_QBUF) and starts the stream (VIDIOC_STREAMON).
  void streamOn();
  /// Stops the stream: the driver gives every buffer back (harmless when not streaming).
  void streamOff();
  /// The oldest filled buffer (VIDIOC_DQBUF); false when none is ready yet (EAGAIN). A node
  /// that has gone (ENODEV, EIO) is "the camera was unplugged mid-stream".
  bool dequeue(v4l2_buffer& b);
  /// The bytes the driver filled in buffer `b` (bytesused, within the mapping).
  const std::uint8_t* data(const v4l2_buffer& b) const { return maps_[b.index].data(); }
  std::size_t bytes(const v4l2_buffer& b) const;
  /// Hands `b` back to the driver (VIDIOC_QBUF). Read what `b` says first: the driver rewrites it.
  void requeue(v4l2_buffer& b);
  std::size_t size() const { return maps_.size(); }

 private:
  void release();
  int fd_;
  v4l2_buf_type type_;
  std::string name_;
  std::vector<MappedBuffer> maps_;
  bool streaming_ = false;
};

}  // namespace lp
