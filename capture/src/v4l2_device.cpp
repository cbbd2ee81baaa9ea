#include "v4l2_device.h"

#include <fcntl.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

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

void UniqueFd::reset(int fd) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = fd;
}

}  // namespace lp
