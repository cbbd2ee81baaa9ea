#include "v4l2_device.h"

#include <fcntl.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "liveprobe/capture/v4l2.h"
#include "liveprobe/sh/error.h"

namespace lp {

int openV4l2Node(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd >= 0) return fd;
  const int e = errno;
  switch (e) {
    case ENOENT:
      throw Error(path + ": open: no such device");
    case EACCES:
      throw Error(path +
                  ": open: permission denied (camera nodes belong to the video group: sudo "
                  "usermod -aG video $USER, then log in again)");
    case EBUSY:
      throw Error(path + ": open: device busy (another program is using it)");
    default:
      throw Error(path + ": open: " + std::strerror(e));
  }
}

int v4l2Ioctl(int fd, unsigned long request, void* arg) {
  int r;
  do r = ::ioctl(fd, request, arg);
  while (r == -1 && errno == EINTR);
  return r;
}

MappedBuffer::MappedBuffer(int fd, const v4l2_buffer& b) : length_(b.length) {
  void* p = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, b.m.offset);
  start_ = p == MAP_FAILED ? nullptr : p;
}

MappedBuffer::MappedBuffer(MappedBuffer&& o) noexcept : start_(o.start_), length_(o.length_) {
  o.start_ = nullptr;
}

MappedBuffer::~MappedBuffer() {
  if (start_) ::munmap(start_, length_);
}

void throwV4l2(const std::string& name, const std::string& what, int err) {
  std::string why = std::strerror(err);
  if (err == ENODEV) why = "the camera was unplugged or has gone (ENODEV)";
  throw Error(name + ": " + what + ": " + why);
}

V4l2Queue::V4l2Queue(int fd, v4l2_buf_type type, std::uint32_t count, std::uint32_t least,
                     std::string name)
    : fd_(fd), type_(type), name_(std::move(name)) {
  v4l2_requestbuffers req{};
  req.count = std::max(count, least);
  req.type = type_;
  req.memory = V4L2_MEMORY_MMAP;
  if (v4l2Ioctl(fd_, VIDIOC_REQBUFS, &req) < 0) {
    const int e = errno;
    if (e == EBUSY)
      throw Error(name_ + ": device busy (VIDIOC_REQBUFS: another program is using it)");
    throwV4l2(name_, "VIDIOC_REQBUFS", e);
  }
  try {
    if (req.count < least)
      throw Error(name_ + ": VIDIOC_REQBUFS granted " + std::to_string(req.count) +
                  " buffers, need at least " + std::to_string(least));
    maps_.reserve(req.count);
    for (std::uint32_t i = 0; i < req.count; ++i) {
      v4l2_buffer b{};
      b.type = type_;
      b.memory = V4L2_MEMORY_MMAP;
      b.index = i;
      if (v4l2Ioctl(fd_, VIDIOC_QUERYBUF, &b) < 0) throwV4l2(name_, "VIDIOC_QUERYBUF", errno);
      maps_.emplace_back(fd_, b);
      if (!maps_.back().valid()) throwV4l2(name_, "mmap", errno);
    }
  } catch (...) {
    release();  // give back what was granted
    throw;
  }
}

V4l2Queue::~V4l2Queue() {
  if (streaming_) streamOff();
  release();
}

void V4l2Queue::release() {
  maps_.clear();  // unmaps
  v4l2_requestbuffers req{};
  req.count = 0;
  req.type = type_;
  req.memory = V4L2_MEMORY_MMAP;
  v4l2Ioctl(fd_, VIDIOC_REQBUFS, &req);  // frees the driver's buffers; fails harmlessly on ENODEV
}

void V4l2Queue::streamOn() {
  for (std::size_t i = 0; i < maps_.size(); ++i) {
    v4l2_buffer b{};
    b.type = type_;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = std::uint32_t(i);
    if (v4l2Ioctl(fd_, VIDIOC_QBUF, &b) < 0) {
      const int e = errno;
      streamOff();
      throwV4l2(name_, "VIDIOC_QBUF", e);
    }
  }
  int type = type_;
  if (v4l2Ioctl(fd_, VIDIOC_STREAMON, &type) < 0) {
    const int e = errno;
    streamOff();
    throwV4l2(name_, "VIDIOC_STREAMON", e);
  }
  streaming_ = true;
}

void V4l2Queue::streamOff() {
  int type = type_;
  v4l2Ioctl(fd_, VIDIOC_STREAMOFF, &type);  // returns every queued buffer; harmless when stopped
  streaming_ = false;
}

bool V4l2Queue::dequeue(v4l2_buffer& b) {
  b = {};
  b.type = type_;
  b.memory = V4L2_MEMORY_MMAP;
  if (v4l2Ioctl(fd_, VIDIOC_DQBUF, &b) < 0) {
    const int e = errno;
    if (e == EAGAIN) return false;
    if (e == ENODEV || e == EIO)
      throw Error(name_ + ": the camera was unplugged mid-stream (" + std::strerror(e) + ")");
    throwV4l2(name_, "VIDIOC_DQBUF", e);
  }
  if (b.index >= maps_.size())
    throw Error(name_ + ": driver returned buffer " + std::to_string(b.index));
  return true;
}

std::size_t V4l2Queue::bytes(const v4l2_buffer& b) const {
  return std::min<std::size_t>(b.bytesused, maps_[b.index].length());
}

void V4l2Queue::requeue(v4l2_buffer& b) {
  if (v4l2Ioctl(fd_, VIDIOC_QBUF, &b) < 0) {
    const int e = errno;
    if (e == ENODEV) throw Error(name_ + ": the camera was unplugged mid-stream (ENODEV)");
    throwV4l2(name_, "VIDIOC_QBUF", e);
  }
}

void UniqueFd::reset(int fd) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = fd;
}

}  // namespace lp
