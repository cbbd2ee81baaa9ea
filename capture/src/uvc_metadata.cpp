#include "uvc_metadata.h"

#include <fcntl.h>
#include <linux/uvcvideo.h>
#include <linux/videodev2.h>
#include <poll.h>

#include <cerrno>
#include <cstring>

#include "liveprobe/sh/error.h"

#ifndef V4L2_META_FMT_UVC_MSXU_1_5
#define V4L2_META_FMT_UVC_MSXU_1_5 v4l2_fourcc('U', 'V', 'C', 'M')
#endif

namespace lp {

namespace {

template <class T>
T readLe(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);  // host byte order, as the kernel hands it over
  return v;
}

constexpr std::uint8_t kHeaderPts = 0x04, kHeaderScr = 0x08;
constexpr std::uint32_t kCaptureStats = 3;            // MetadataId_CaptureStats
constexpr std::uint32_t kCaptureStatsExposure = 0x1;  // ..._FLAG_EXPOSURETIME

}  // namespace

std::optional<double> parseUvcExposure(const std::uint8_t* data, std::size_t bytes) {
  // Blocks of uvc_meta_buf: ns (8), sof (2), then the payload header, `length` bytes from its
  // own length field: flags, PTS and SCR when flagged, then Microsoft's metadata items.
  std::optional<double> exposure;
  std::size_t at = 0;
  const std::size_t head = offsetof(uvc_meta_buf, length);
  while (at + head + 2 <= bytes) {
    const std::size_t length = data[at + head];
    if (length < 2 || at + head + length > bytes) break;  // a torn block: stop
    const std::uint8_t* h = data + at + head;
    const std::uint8_t flags = h[1];
    std::size_t item = 2 + ((flags & kHeaderPts) ? 4 : 0) + ((flags & kHeaderScr) ? 6 : 0);
    while (item + 8 <= length) {
      const auto id = readLe<std::uint32_t>(h + item);
      const auto size = readLe<std::uint32_t>(h + item + 4);
      if (size < 8 || item + size > length) break;
      if (id == kCaptureStats && size >= 24 &&
          (readLe<std::uint32_t>(h + item + 8) & kCaptureStatsExposure)) {
        const auto t100ns = readLe<std::uint64_t>(h + item + 16);
        if (t100ns > 0) exposure = double(t100ns) * 1e-7;
      }
      item += size;
    }
    at += head + length;
  }
  return exposure;
}

UvcMetadata::UvcMetadata(const std::string& path, const std::string& bus) : path_(path) {
  fd_.reset(::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC));
  if (!fd_.isValid()) throw Error(path + ": no metadata node here (" + std::strerror(errno) + ")");
  v4l2_capability cap{};
  if (v4l2Ioctl(fd_.get(), VIDIOC_QUERYCAP, &cap) < 0)
    throw Error(path + ": not a V4L2 device (VIDIOC_QUERYCAP: " + std::strerror(errno) + ")");
  const std::uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_META_CAPTURE) || !(caps & V4L2_CAP_STREAMING))
    throw Error(path + ": not a metadata node (no V4L2_CAP_META_CAPTURE with streaming)");
  if (reinterpret_cast<const char*>(cap.bus_info) != bus)
    throw Error(path + ": the metadata node of another camera (" +
                reinterpret_cast<const char*>(cap.bus_info) + ", not " + bus + ")");
  // The formats that carry the whole header; V4L2_META_FMT_UVC keeps only its first 12 bytes.
  std::uint32_t chosen = 0;
  for (std::uint32_t i = 0;; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_META_CAPTURE;
    if (v4l2Ioctl(fd_.get(), VIDIOC_ENUM_FMT, &d) < 0) break;
    if (d.pixelformat == V4L2_META_FMT_UVC_MSXU_1_5 || d.pixelformat == V4L2_META_FMT_D4XX)
      chosen = d.pixelformat;
  }
  if (!chosen)
    throw Error(path +
                ": the camera's metadata carries no exposure times (no "
                "V4L2_META_FMT_UVC_MSXU_1_5 format: a camera without Microsoft's UVC "
                "extensions, or a kernel that does not offer them)");
  v4l2_format f{};
  f.type = V4L2_BUF_TYPE_META_CAPTURE;
  f.fmt.meta.dataformat = chosen;
  if (v4l2Ioctl(fd_.get(), VIDIOC_S_FMT, &f) < 0 || f.fmt.meta.dataformat != chosen)
    throw Error(path + ": VIDIOC_S_FMT of the metadata format failed");
  queue_ = std::make_unique<V4l2Queue>(fd_.get(), V4L2_BUF_TYPE_META_CAPTURE, 8, 1, path);
  queue_->streamOn();
}

UvcMetadata::~UvcMetadata() = default;  // the queue stops the stream and frees its buffers

void UvcMetadata::drain() {
  v4l2_buffer b;
  while (queue_->dequeue(b)) {  // until EAGAIN: nothing more for now
    if (!(b.flags & V4L2_BUF_FLAG_ERROR))
      seen_[b.sequence] = parseUvcExposure(queue_->data(b), queue_->bytes(b));
    queue_->requeue(b);
    while (seen_.size() > 64) seen_.erase(seen_.begin());
  }
}

std::optional<double> UvcMetadata::exposureOf(std::uint32_t sequence, int timeoutMs) {
  for (int waited = 0;; waited += 5) {
    drain();
    if (auto it = seen_.find(sequence); it != seen_.end()) return it->second;
    if (!seen_.empty() && seen_.rbegin()->first > sequence) return std::nullopt;  // lost
    if (waited >= timeoutMs) return std::nullopt;
    pollfd p{fd_.get(), POLLIN, 0};
    ::poll(&p, 1, 5);
  }
}

}  // namespace lp
