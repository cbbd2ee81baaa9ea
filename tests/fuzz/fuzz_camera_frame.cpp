// libFuzzer target: the V4L2 path's frame decoders (MJPEG, YUYV, NV12, RGB24). The first bytes
// are the negotiated format (fourcc, size, stride, MJPEG scale), the rest the buffer a camera
// filled. Any buffer ends in a frame of the negotiated size (or its MJPEG reduction) or in an
// empty frame (dropped): never a crash or a read beyond the buffer.
#include <linux/videodev2.h>

#include <cstdint>
#include <cstdlib>
#include <vector>

#include "liveprobe/capture/v4l2.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 5) return 0;
  static const std::uint32_t kFourcc[] = {V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_JPEG, V4L2_PIX_FMT_YUYV,
                                          V4L2_PIX_FMT_NV12, V4L2_PIX_FMT_RGB24};
  lp::CameraBuffer b;
  b.fourcc = kFourcc[data[0] % 5];
  b.width = 1 + data[1] % 96;
  b.height = 1 + data[2] % 96;
  b.bytesPerLine = std::size_t(data[3]) * 2;  // may be short of a row: must be refused
  const int reduce = 1 << (data[4] % 4);
  // The buffer in its own allocation, so that ASan sees any read past its end.
  const std::vector<std::uint8_t> bytes(data + 5, data + size);
  b.data = bytes.data();
  b.bytes = bytes.size();
  lp::Frame f;
  lp::decodeCameraFrame(b, reduce, f);
  if (f.width != 0) {
    const bool mjpeg = b.fourcc == V4L2_PIX_FMT_MJPEG || b.fourcc == V4L2_PIX_FMT_JPEG;
    const int r = mjpeg ? reduce : 1;
    if (f.width != (b.width + r - 1) / r || f.height != (b.height + r - 1) / r ||
        f.bgr8.size() != std::size_t(f.width) * f.height * 3)
      std::abort();
  }
  return 0;
}
