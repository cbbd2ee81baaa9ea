#pragma once
// A V4L2 capture source written against linux/videodev2.h and the kernel's V4L2 documentation
// (https://docs.kernel.org/userspace-api/media/v4l/): memory-mapped streaming I/O with poll(),
// MJPEG / YUYV / NV12 / RGB24 conversion to 8-bit BGR, and the camera controls a light probe needs
// (exposure, gain, white balance), with locking after auto-exposure settles.
// Structure after libcamera's V4L2VideoDevice: the constructor cannot fail; explicit verbs with
// states (open, setFormat, allocateBuffers, streamOn, streamOff, close) that can; the fd and the
// mappings have RAII owners; buffers are requested and released as a pair with a rollback;
// streamOff() is idempotent and returns every buffer, and a stopped source can start again.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "liveprobe/frame/exposure_control.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/sh/error.h"

namespace lp {

/// Move-only owner of a file descriptor.
class UniqueFd {
 public:
  UniqueFd() = default;
  explicit UniqueFd(int fd) : fd_(fd) {}
  UniqueFd(UniqueFd&& o) noexcept : fd_(o.release()) {}
  UniqueFd& operator=(UniqueFd&& o) noexcept {
    reset(o.release());
    return *this;
  }
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  ~UniqueFd() { reset(); }
  int get() const { return fd_; }
  bool isValid() const { return fd_ >= 0; }
  int release() {
    const int f = fd_;
    fd_ = -1;
    return f;
  }
  void reset(int fd = -1);

 private:
  int fd_ = -1;
};

/// The pixel formats liveprobe converts, as V4L2 fourcc codes. H.264 and HEVC are decoded with
/// FFmpeg's libavcodec (a build with the network backend).
enum class CameraFormat : std::uint8_t { Auto, Mjpeg, Yuyv, Nv12, Rgb24, H264, Hevc };
inline std::string_view cameraFormatName(CameraFormat f) {
  switch (f) {
    case CameraFormat::Auto:
      return "auto";
    case CameraFormat::Mjpeg:
      return "mjpeg";
    case CameraFormat::Yuyv:
      return "yuyv";
    case CameraFormat::Nv12:
      return "nv12";
    case CameraFormat::Rgb24:
      return "rgb24";
    case CameraFormat::H264:
      return "h264";
    case CameraFormat::Hevc:
      return "hevc";
  }
  return "?";
}

/// "mjpeg", "yuyv", "nv12", "rgb24", "h264", "hevc" or "auto"; throws lp::Error. (Inline: the
/// command line reads it in every build, with V4L2 or without.)
inline CameraFormat parseCameraFormat(std::string_view name) {
  for (CameraFormat f :
       {CameraFormat::Auto, CameraFormat::Mjpeg, CameraFormat::Yuyv, CameraFormat::Nv12,
        CameraFormat::Rgb24, CameraFormat::H264, CameraFormat::Hevc})
    if (cameraFormatName(f) == name) return f;
  throw Error("unknown camera format " + std::string(name) +
              " (expected mjpeg, yuyv, nv12, rgb24, h264, hevc or auto)");
}

/// One buffer as a camera filled it, in the format negotiated with VIDIOC_S_FMT.
struct CameraBuffer {
  std::uint32_t fourcc = 0;      ///< V4L2_PIX_FMT_*
  int width = 0, height = 0;     ///< negotiated frame size
  std::size_t bytesPerLine = 0;  ///< negotiated row stride (uncompressed formats)
  const std::uint8_t* data = nullptr;
  std::size_t bytes = 0;  ///< bytes used (never more than the buffer holds)
};

/// Decodes a camera buffer into a BGR8 frame; MJPEG at 1/`mjpegReduce` scale (1, 2, 4, 8). (H.264
/// and HEVC frames depend on the frames before them: V4l2Source decodes them with its own
/// decoder; here they give an empty frame.) A
/// corrupt or short buffer, a stride shorter than a row, or a compressed frame whose size is not
/// the negotiated one leaves an empty frame (width 0), which the caller counts as dropped.
void decodeCameraFrame(const CameraBuffer& buffer, int mjpegReduce, Frame& frame);

struct CameraSettings {
  std::string device;  ///< /dev/videoN
  /// Auto: MJPEG, then YUYV, NV12, RGB24, then H.264 and HEVC (a camera that offers nothing else)
  CameraFormat format = CameraFormat::Auto;
  int width = 0, height = 0;  ///< 0: the largest the format offers
  double fps = 0;             ///< 0: the driver's default
  int buffers = 4;            ///< asked for; at least 3 must be granted
  int timeoutMs = 2000;       ///< no frame for this long: the camera stopped sending
  int mjpegReduce = 1;        ///< decode MJPEG at 1/2, 1/4 or 1/8 scale (libjpeg's DCT scaling)
  /// The camera's UVC metadata node, streamed beside the video for each frame's exposure time
  /// (empty: none). Frames then carry the exposure the camera reports, not the one asked for.
  std::string metadataDevice;
};

/// The exposure time, in seconds, in one buffer of a UVC metadata node
/// (V4L2_META_FMT_UVC_MSXU_1_5: uvc_meta_buf blocks whose payload headers hold Microsoft's
/// capture statistics); nullopt when no block carries one. Torn blocks end the parse.
std::optional<double> parseUvcExposure(const std::uint8_t* data, std::size_t bytes);

class V4l2Source;

/// Opens and starts the camera `settings` names, with its metadata node (metadataDevice) where
/// one is named. Where that node cannot stream (most webcams have none: their exposures are then
/// told from the frames), the camera is started without it, unless `metadataRequired` (a node the
/// user named must work). Throws lp::Error naming the device or the node.
std::unique_ptr<V4l2Source> startCamera(CameraSettings settings, bool metadataRequired);

/// The metadata node uvcvideo creates beside a video node: /dev/videoN -> /dev/video(N+1).
std::string siblingMetadataNode(const std::string& videoNode);

class UvcMetadata;
class V4l2Queue;
class VideoDecoder;

struct CameraControl {
  std::uint32_t id = 0;
  std::string name;
  int type = 0;
  std::int32_t minimum = 0, maximum = 0, step = 0, defaultValue = 0, value = 0;
};

struct CameraFrameSize {
  std::uint32_t fourcc = 0;
  int width = 0, height = 0;
  std::vector<double> fps;  ///< discrete rates, or {min, max} of a stepwise range
};

struct CameraInfo {
  std::string path, card, driver, bus;
  /// A video-capture node. UVC cameras also expose a metadata node (V4L2_CAP_META_CAPTURE):
  /// it answers QUERYCAP but carries no video; queryCamera() then lists nothing else.
  bool videoCapture = true;
  std::string kind;  ///< what it is when not video capture ("metadata", "output", ...)
  std::vector<CameraFrameSize> modes;
  std::vector<CameraControl> controls;
};

/// A V4L2 pixel format code as its four characters ("MJPG").
std::string fourccText(std::uint32_t fourcc);

/// Queries a device without streaming (formats, sizes, rates, controls). Throws lp::Error.
CameraInfo queryCamera(const std::string& path);

/// The exposure values a lock read from the camera's automatic controls and fixed.
struct LockedExposure {
  std::optional<std::int32_t> exposure100us, gain, whiteBalanceK;
};

class V4l2Source final : public FrameSource, public ExposureControl {
 public:
  explicit V4l2Source(CameraSettings settings) noexcept;
  ~V4l2Source() override;

  /// The source's states, in the order of the kernel's calls (after libcamera's
  /// V4L2VideoDevice): each verb below moves one step and needs the state before it.
  enum class State : std::uint8_t {
    Closed,      ///< no device
    Open,        ///< the device is open and is a streaming video-capture node
    Configured,  ///< format, size and rate are set (VIDIOC_S_FMT, VIDIOC_S_PARM)
    Ready,       ///< buffers are allocated and mapped (VIDIOC_REQBUFS, mmap)
    Streaming,   ///< every buffer was queued and VIDIOC_STREAMON succeeded
  };
  static std::string_view stateName(State s);
  State state() const { return state_; }

  /// Closed -> Open: opens the device and checks its capabilities.
  void open();
  /// Open -> Configured: negotiates format, size and rate from the settings.
  void setFormat();
  /// Configured -> Ready: requests at least 3 buffers and maps them (rolled back on failure).
  void allocateBuffers();
  /// Ready -> Streaming: queues every buffer and starts streaming. After streamOff() a source
  /// can stream again; the sequence gap across the stop is not counted as dropped frames.
  void streamOn();
  /// Streaming -> Ready: stops streaming; the driver returns every buffer (idempotent).
  void streamOff();
  /// Any state -> Closed: stops, frees the buffers, unmaps them and closes (idempotent).
  void close();
  /// open(), setFormat(), allocateBuffers(), streamOn(); closes again if one fails.
  /// Each verb throws lp::Error "DEVICE: OPERATION: why", and one called in the wrong state
  /// says which state it needs.
  void start();

  /// Lets auto-exposure and auto white balance settle for `seconds` of streaming, then turns the
  /// automatic modes off and writes back the values they reached (exposure, gain, white
  /// balance), in that order: a driver ignores manual values while its auto mode is on.
  LockedExposure lockExposure(double seconds);

  /// Whether frames carry the exposure the camera reports (a metadata node is streaming).
  bool reportsExposure() const { return metadata_ != nullptr; }
  /// ExposureControl, for bracketing and calibration (liveprobe/hdr/bracketing.h,
  /// liveprobe/hdr/calibrate.h): the control's range, and a request written as it is (frames
  /// without metadata keep carrying the locked exposure; those with it say what they were taken
  /// with).
  std::pair<std::int32_t, std::int32_t> exposureRange() override;
  void requestExposure(std::int32_t exposure100us) override;

  bool next(Frame& frame) override;
  bool rewind() override { return false; }
  std::string describe() const override;
  double fps() const override { return fps_; }
  std::size_t skippedFrames() const override { return dropped_; }

  /// What the driver actually set.
  std::uint32_t fourcc() const { return fourcc_; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  [[noreturn]] void fail(const std::string& what, int err) const;
  void require(State needed, const char* verb) const;
  int xioctl(unsigned long request, void* arg);
  // setFormat()'s steps: the format (asked for, or the first liveprobe converts), the largest
  // size it offers (when none was asked for), and the frame rate.
  std::uint32_t chooseFourcc();
  std::pair<int, int> largestSize(std::uint32_t fourcc);
  void setRate();
  /// The exposure this frame was taken with, from the metadata node, where it reports one.
  void readFrameExposure(Frame& frame, std::uint32_t sequence);
  /// A frame's numbering, times and exposure, once its pixels are in `frame`.
  void finishFrame(Frame& frame, std::uint32_t sequence, double timestamp);
  /// H.264 or HEVC: one buffer to the decoder (a damaged one, or a sequence gap, makes it wait
  /// for the next key frame), and a frame it has ready.
  void sendToDecoder(const std::uint8_t* data, std::size_t bytes, bool damaged, bool gap,
                     std::uint32_t sequence, double timestamp);
  bool takeDecoded(Frame& frame);
  std::optional<std::int32_t> getControl(std::uint32_t id);
  /// Writes a control and reads it back. Returns false when the camera has no such control
  /// (VIDIOC_QUERYCTRL: EINVAL); a refused write, or a value that does not read back, is an
  /// lp::Error naming the control and the value.
  bool setControl(std::uint32_t id, std::int32_t value);
  /// The driver's name of a control ("Gain"), or its id in hex.
  std::string controlName(std::uint32_t id);

  CameraSettings settings_;
  UniqueFd fd_;
  State state_ = State::Closed;
  std::unique_ptr<V4l2Queue> queue_;  ///< the buffers, from allocateBuffers() to close()
  std::uint32_t fourcc_ = 0;
  int width_ = 0, height_ = 0;
  std::size_t bytesPerLine_ = 0, sizeImage_ = 0;
  double fps_ = 0;
  std::optional<std::uint32_t> lastSequence_;
  std::size_t dropped_ = 0;
  double firstTimestamp_ = -1;
  /// After lockExposure() the exposure and gain no longer change: no per-frame control reads.
  std::optional<std::int32_t> lockedExposure_, lockedGain_;
  bool locked_ = false;
  std::string card_, bus_;
  std::unique_ptr<UvcMetadata> metadata_;
  /// H.264 or HEVC (its deleter is set where it is made: a build without FFmpeg has none).
  std::unique_ptr<VideoDecoder, void (*)(VideoDecoder*)> decoder_{nullptr, nullptr};
  bool monotonic_ = true;  ///< the driver's timestamps are CLOCK_MONOTONIC
};

}  // namespace lp
