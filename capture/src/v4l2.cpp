#include "liveprobe/capture/v4l2.h"

#include <linux/videodev2.h>
#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "camera_jpeg.h"
#include "liveprobe/backends.h"
#include "liveprobe/sh/error.h"
#include "uvc_metadata.h"
#include "v4l2_device.h"
#if LIVEPROBE_WITH_NETWORK
#include "video_decoder.h"
#endif

namespace lp {

std::string fourccText(std::uint32_t f) {
  std::string s;
  for (int i = 0; i < 4; ++i) s += char((f >> (8 * i)) & 0xFF);
  return s;
}

namespace {

std::uint32_t fourccOf(CameraFormat f) {
  switch (f) {
    case CameraFormat::Mjpeg:
      return V4L2_PIX_FMT_MJPEG;
    case CameraFormat::Yuyv:
      return V4L2_PIX_FMT_YUYV;
    case CameraFormat::Nv12:
      return V4L2_PIX_FMT_NV12;
    case CameraFormat::Rgb24:
      return V4L2_PIX_FMT_RGB24;
    case CameraFormat::H264:
      return V4L2_PIX_FMT_H264;
    case CameraFormat::Hevc:
      return V4L2_PIX_FMT_HEVC;
    case CameraFormat::Auto:
      return 0;
  }
  return 0;
}

/// A stream of frames that depend on each other (decoded by V4l2Source's VideoDecoder).
bool isVideoCodec(std::uint32_t fourcc) {
  return fourcc == V4L2_PIX_FMT_H264 || fourcc == V4L2_PIX_FMT_HEVC;
}

/// An H.264 or HEVC buffer as UVC sends it: an Annex B byte stream, starting with a start code.
bool startsAnnexB(const std::uint8_t* p, std::size_t n) {
  return (n >= 4 && p[0] == 0 && p[1] == 0 && p[2] == 1) ||
         (n >= 5 && p[0] == 0 && p[1] == 0 && p[2] == 0 && p[3] == 1);
}

}  // namespace

V4l2Source::V4l2Source(CameraSettings settings) noexcept : settings_(std::move(settings)) {}

V4l2Source::~V4l2Source() { close(); }

void V4l2Source::fail(const std::string& what, int err) const {
  throwV4l2(settings_.device, what, err);
}

int V4l2Source::xioctl(unsigned long request, void* arg) {
  return v4l2Ioctl(fd_.get(), request, arg);
}

std::string_view V4l2Source::stateName(State s) {
  switch (s) {
    case State::Closed:
      return "closed";
    case State::Open:
      return "open";
    case State::Configured:
      return "configured";
    case State::Ready:
      return "ready (buffers allocated)";
    case State::Streaming:
      return "streaming";
  }
  return "?";
}

void V4l2Source::require(State needed, const char* verb) const {
  if (state_ != needed)
    throw Error(settings_.device + ": " + verb + ": needs the source " +
                std::string(stateName(needed)) + ", it is " + std::string(stateName(state_)));
}

void V4l2Source::start() {
  try {
    open();
    setFormat();
    allocateBuffers();
    if (!settings_.metadataDevice.empty()) try {
        metadata_ = std::make_unique<UvcMetadata>(settings_.metadataDevice, bus_);
      } catch (const Error& e) {
        throw Error(settings_.device + ": no per-frame exposure times: " + e.what());
      }
    streamOn();
  } catch (...) {
    close();
    throw;
  }
}

void V4l2Source::open() {
  require(State::Closed, "open");
  fd_.reset(openV4l2Node(settings_.device));
  v4l2_capability cap{};
  if (xioctl(VIDIOC_QUERYCAP, &cap) < 0) {
    const int e = errno;
    fd_.reset();
    throw Error(settings_.device + ": VIDIOC_QUERYCAP: " + std::strerror(e) +
                " (not a V4L2 video device)");
  }
  card_ = reinterpret_cast<const char*>(cap.card);
  bus_ = reinterpret_cast<const char*>(cap.bus_info);
  const std::uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  std::string missing;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE))
    missing = "not a single-planar video capture device (" + card_ + ")";
  else if (!(caps & V4L2_CAP_STREAMING))
    missing = "the device has no streaming I/O";
  if (!missing.empty()) {
    fd_.reset();
    throw Error(settings_.device + ": VIDIOC_QUERYCAP: " + missing);
  }
  state_ = State::Open;
}

void V4l2Source::streamOn() {
  require(State::Ready, "streamOn");
  queue_->streamOn();
  lastSequence_.reset();  // a restart's sequence gap is not lost frames
#if LIVEPROBE_WITH_NETWORK
  if (decoder_) decoder_->lost();  // a new stream: its first key frame starts the pictures
#endif
  state_ = State::Streaming;
}

std::uint32_t V4l2Source::chooseFourcc() {
  std::vector<std::uint32_t> offered;
  for (std::uint32_t i = 0;; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(VIDIOC_ENUM_FMT, &d) < 0) break;  // EINVAL ends the list
    offered.push_back(d.pixelformat);
  }
  auto offers = [&](std::uint32_t f) {
    return std::find(offered.begin(), offered.end(), f) != offered.end();
  };
  std::string list;
  for (auto f : offered) list += (list.empty() ? "" : ", ") + fourccText(f);
  if (const std::uint32_t want = fourccOf(settings_.format); want != 0) {
    if (!offers(want))
      throw Error(settings_.device + ": VIDIOC_ENUM_FMT: does not offer " + fourccText(want) +
                  " (it offers " + list + ")");
    if (isVideoCodec(want) && !LIVEPROBE_WITH_NETWORK)
      throw Error(settings_.device + ": --pixel-format " +
                  std::string(cameraFormatName(settings_.format)) +
                  ": this liveprobe was built without FFmpeg's libavcodec (the network backend), "
                  "which decodes it");
    return want;
  }
  for (CameraFormat f : {CameraFormat::Mjpeg, CameraFormat::Yuyv, CameraFormat::Nv12,
                         CameraFormat::Rgb24, CameraFormat::H264, CameraFormat::Hevc})
    if (offers(fourccOf(f)) && (LIVEPROBE_WITH_NETWORK || !isVideoCodec(fourccOf(f))))
      return fourccOf(f);
  throw Error(settings_.device +
              ": VIDIOC_ENUM_FMT: offers no format liveprobe converts (it offers " + list + ")");
}

std::pair<int, int> V4l2Source::largestSize(std::uint32_t fourcc) {
  int w = 0, h = 0;
  for (std::uint32_t i = 0;; ++i) {
    v4l2_frmsizeenum s{};
    s.index = i;
    s.pixel_format = fourcc;
    if (xioctl(VIDIOC_ENUM_FRAMESIZES, &s) < 0) break;
    if (s.type != V4L2_FRMSIZE_TYPE_DISCRETE)
      return {int(s.stepwise.max_width), int(s.stepwise.max_height)};
    if (int(s.discrete.width * s.discrete.height) > w * h)
      w = int(s.discrete.width), h = int(s.discrete.height);
  }
  return {w, h};
}

void V4l2Source::setRate() {
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (settings_.fps > 0 && xioctl(VIDIOC_G_PARM, &parm) == 0 &&
      (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME)) {
    parm.parm.capture.timeperframe = {1000, std::uint32_t(std::lround(settings_.fps * 1000))};
    if (xioctl(VIDIOC_S_PARM, &parm) < 0) fail("VIDIOC_S_PARM", errno);
  }
  parm = {};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(VIDIOC_G_PARM, &parm) == 0 && parm.parm.capture.timeperframe.numerator > 0)
    fps_ = double(parm.parm.capture.timeperframe.denominator) /
           parm.parm.capture.timeperframe.numerator;
  else
    fps_ = settings_.fps > 0 ? settings_.fps : 30.0;
}

void V4l2Source::setFormat() {
  require(State::Open, "setFormat");
  const std::uint32_t want = chooseFourcc();
  auto [w, h] = std::pair(settings_.width, settings_.height);
  if (w <= 0 || h <= 0) std::tie(w, h) = largestSize(want);
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = std::uint32_t(std::max(w, 0));
  fmt.fmt.pix.height = std::uint32_t(std::max(h, 0));
  fmt.fmt.pix.pixelformat = want;
  fmt.fmt.pix.field = V4L2_FIELD_ANY;
  if (xioctl(VIDIOC_S_FMT, &fmt) < 0) fail("VIDIOC_S_FMT " + fourccText(want), errno);
  // S_FMT adjusts what it cannot do: read back what the driver actually set.
  if (fmt.fmt.pix.pixelformat != want)
    throw Error(settings_.device + ": VIDIOC_S_FMT: asked for " + fourccText(want) +
                ", the driver set " + fourccText(fmt.fmt.pix.pixelformat));
  fourcc_ = fmt.fmt.pix.pixelformat;
  width_ = int(fmt.fmt.pix.width);
  height_ = int(fmt.fmt.pix.height);
  bytesPerLine_ = fmt.fmt.pix.bytesperline;
  sizeImage_ = fmt.fmt.pix.sizeimage;
  if (width_ <= 0 || height_ <= 0)
    throw Error(settings_.device + ": VIDIOC_S_FMT: the driver set an empty frame size");
#if LIVEPROBE_WITH_NETWORK
  if (isVideoCodec(fourcc_)) try {
      decoder_ = {new VideoDecoder(fourcc_ == V4L2_PIX_FMT_H264 ? "h264" : "hevc"),
                  [](VideoDecoder* d) { delete d; }};
    } catch (const Error& e) {
      throw Error(settings_.device + ": " + e.what());
    }
#endif
  setRate();
  state_ = State::Configured;
}

void V4l2Source::allocateBuffers() {
  require(State::Configured, "allocateBuffers");
  constexpr std::uint32_t kMinBuffers = 3;
  queue_ = std::make_unique<V4l2Queue>(fd_.get(), V4L2_BUF_TYPE_VIDEO_CAPTURE,
                                       std::uint32_t(std::max(settings_.buffers, 0)), kMinBuffers,
                                       settings_.device);
  state_ = State::Ready;
}

void V4l2Source::streamOff() {
  if (state_ != State::Streaming) return;
  queue_->streamOff();
  state_ = State::Ready;
}

void V4l2Source::close() {
  metadata_.reset();
  decoder_.reset();
  queue_.reset();  // stops the stream, gives the buffers back
  fd_.reset();
  state_ = State::Closed;
}

bool V4l2Source::next(Frame& frame) {
  require(State::Streaming, "next");
  for (;;) {
    if (decoder_ && takeDecoded(frame)) return true;  // a frame the decoder held
    pollfd p{fd_.get(), POLLIN, 0};
    const int r = ::poll(&p, 1, settings_.timeoutMs);
    if (r < 0) {
      if (errno == EINTR) continue;  // a signal: poll again
      fail("poll", errno);
    }
    if (r == 0)
      throw Error(settings_.device + ": no frame for " +
                  std::to_string(settings_.timeoutMs / 1000.0).substr(0, 4) +
                  " s: the camera stopped sending");
    v4l2_buffer b;
    if (!queue_->dequeue(b)) continue;  // woken without a frame
    // Gaps in the driver's sequence numbers are frames lost before we saw them.
    const bool gap = lastSequence_ && b.sequence > *lastSequence_ + 1;
    if (gap) dropped_ += b.sequence - *lastSequence_ - 1;
    lastSequence_ = b.sequence;
    // What the driver says about this frame, read before QBUF hands the buffer back (the
    // driver rewrites the struct then).
    const bool corrupt = b.flags & V4L2_BUF_FLAG_ERROR;
    const double t = double(b.timestamp.tv_sec) + double(b.timestamp.tv_usec) * 1e-6;
    // The timestamp is CLOCK_MONOTONIC when the driver says so (the kernel's default for UVC).
    monotonic_ = (b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
    const std::uint32_t sequence = b.sequence;
    const std::uint8_t* data = queue_->data(b);
    const std::size_t used = queue_->bytes(b);
    if (decoder_)
      sendToDecoder(data, used, corrupt, gap, sequence, t);  // copied: before QBUF
    else if (!corrupt)
      decodeCameraFrame({fourcc_, width_, height_, bytesPerLine_, data, used},
                        settings_.mjpegReduce, frame);
    queue_->requeue(b);
    if (decoder_) continue;  // its frames come out of takeDecoded()
    if (corrupt || frame.width == 0) {
      ++dropped_;
      continue;
    }
    finishFrame(frame, sequence, t);
    return true;
  }
}

void V4l2Source::finishFrame(Frame& frame, std::uint32_t sequence, double t) {
  if (firstTimestamp_ < 0) firstTimestamp_ = t;
  frame.sequence = sequence;
  frame.timestamp = t - firstTimestamp_;
  frame.captureTime = monotonic_ ? t : -1.0;
  // The exposure and gain in force: read per frame while the automatic modes may change them.
  frame.exposure100us = locked_ ? lockedExposure_ : getControl(V4L2_CID_EXPOSURE_ABSOLUTE);
  frame.gain = locked_ ? lockedGain_ : getControl(V4L2_CID_GAIN);
  // 1 / exposure time in seconds: radiance in "per second" units, comparable between frames
  // and runs with different exposures.
  frame.radianceScale =
      frame.exposure100us && *frame.exposure100us > 0 ? 1.0 / (*frame.exposure100us * 1e-4) : 1.0;
  // What the camera says this frame was taken with, where it says it (the metadata node).
  frame.exposureReported = false;
  readFrameExposure(frame, sequence);
}

#if LIVEPROBE_WITH_NETWORK
void V4l2Source::sendToDecoder(const std::uint8_t* data, std::size_t bytes, bool damaged, bool gap,
                               std::uint32_t sequence, double t) {
  // A frame lost before us leaves the ones that refer to it without their reference.
  if (gap) decoder_->lost();
  // A buffer the driver flagged, one that is not a byte stream, or one the decoder refuses is a
  // frame lost here.
  if (damaged || !startsAnnexB(data, bytes) || !decoder_->send(data, bytes, sequence, t)) {
    decoder_->lost();
    ++dropped_;
  }
}

bool V4l2Source::takeDecoded(Frame& frame) {
  VideoDecoder::Decoded info;
  std::size_t withheld = 0;
  bool got = false;
  try {
    got = decoder_->receive(frame, info, withheld);
  } catch (const Error& e) {
    throw Error(settings_.device + ": " + e.what());
  }
  dropped_ += withheld;
  if (!got) return false;
  // Its own buffer's number and time: the decoder's delay counts in the latency.
  finishFrame(frame, std::uint32_t(info.pts), info.arrival);
  return true;
}
#else  // never reached: a build without FFmpeg makes no decoder (chooseFourcc)
void V4l2Source::sendToDecoder(const std::uint8_t*, std::size_t, bool, bool, std::uint32_t,
                               double) {}
bool V4l2Source::takeDecoded(Frame&) { return false; }
#endif

void V4l2Source::readFrameExposure(Frame& frame, std::uint32_t sequence) {
  if (!metadata_) return;
  const auto t = metadata_->exposureOf(sequence, 100);
  if (!t) return;
  frame.radianceScale = 1.0 / *t;
  frame.exposure100us = std::int32_t(std::lround(*t * 1e4));
  frame.exposureReported = true;
}

std::pair<std::int32_t, std::int32_t> V4l2Source::exposureRange() {
  require(State::Streaming, "exposureRange");
  v4l2_queryctrl q{};
  q.id = V4L2_CID_EXPOSURE_ABSOLUTE;
  if (xioctl(VIDIOC_QUERYCTRL, &q) < 0 || (q.flags & V4L2_CTRL_FLAG_DISABLED))
    throw Error(settings_.device + ": the camera has no exposure time control " +
                "(V4L2_CID_EXPOSURE_ABSOLUTE): it cannot bracket");
  return {q.minimum, q.maximum};
}

void V4l2Source::requestExposure(std::int32_t exposure100us) {
  v4l2_control c{V4L2_CID_EXPOSURE_ABSOLUTE, exposure100us};
  if (xioctl(VIDIOC_S_CTRL, &c) < 0)
    fail("VIDIOC_S_CTRL " + controlName(V4L2_CID_EXPOSURE_ABSOLUTE) + " = " +
             std::to_string(exposure100us) + " (the camera refuses exposure changes)",
         errno);
}

std::unique_ptr<V4l2Source> startCamera(CameraSettings settings, bool metadataRequired) {
  auto camera = std::make_unique<V4l2Source>(settings);
  try {
    camera->start();
  } catch (const Error&) {
    if (settings.metadataDevice.empty() || metadataRequired) throw;
    settings.metadataDevice.clear();
    camera = std::make_unique<V4l2Source>(settings);
    camera->start();
  }
  return camera;
}

std::string siblingMetadataNode(const std::string& videoNode) {
  std::size_t digits = videoNode.size();
  while (digits > 0 && std::isdigit(static_cast<unsigned char>(videoNode[digits - 1]))) --digits;
  if (digits == videoNode.size()) return {};
  return videoNode.substr(0, digits) + std::to_string(std::stoul(videoNode.substr(digits)) + 1);
}

std::optional<std::int32_t> V4l2Source::getControl(std::uint32_t id) {
  v4l2_control c{};
  c.id = id;
  if (xioctl(VIDIOC_G_CTRL, &c) < 0) return std::nullopt;
  return c.value;
}

std::string V4l2Source::controlName(std::uint32_t id) {
  v4l2_queryctrl q{};
  q.id = id;
  if (xioctl(VIDIOC_QUERYCTRL, &q) == 0) return reinterpret_cast<const char*>(q.name);
  char hex[16];
  std::snprintf(hex, sizeof hex, "0x%08x", id);
  return hex;
}

bool V4l2Source::setControl(std::uint32_t id, std::int32_t value) {
  v4l2_queryctrl q{};
  q.id = id;
  if (xioctl(VIDIOC_QUERYCTRL, &q) < 0 || (q.flags & V4L2_CTRL_FLAG_DISABLED))
    return false;  // the camera has no such control: nothing to set
  v4l2_control c{};
  c.id = id;
  c.value = value;
  const std::string what = std::string("VIDIOC_S_CTRL ") + reinterpret_cast<const char*>(q.name) +
                           " = " + std::to_string(value);
  if (xioctl(VIDIOC_S_CTRL, &c) < 0) fail(what, errno);
  const auto back = getControl(id);
  if (back && *back != value)
    throw Error(settings_.device + ": " + what + ": the camera reads back " +
                std::to_string(*back));
  return true;
}

LockedExposure V4l2Source::lockExposure(double seconds) {
  // 1. Automatic modes on (UVC cameras call auto exposure "aperture priority").
  // Aperture priority, or full auto where the menu lacks it.
  v4l2_control c{V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_APERTURE_PRIORITY};
  if (xioctl(VIDIOC_S_CTRL, &c) < 0) setControl(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_AUTO);
  setControl(V4L2_CID_AUTOGAIN, 1);
  setControl(V4L2_CID_AUTO_WHITE_BALANCE, 1);
  // 2. Let them settle on the scene.
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  Frame f;
  while (std::chrono::steady_clock::now() < end) next(f);
  // 3. Read what they reached, 4. turn them off, 5. write the values back.
  LockedExposure locked;
  locked.exposure100us = getControl(V4L2_CID_EXPOSURE_ABSOLUTE);
  locked.gain = getControl(V4L2_CID_GAIN);
  locked.whiteBalanceK = getControl(V4L2_CID_WHITE_BALANCE_TEMPERATURE);
  setControl(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL);
  if (locked.exposure100us) setControl(V4L2_CID_EXPOSURE_ABSOLUTE, *locked.exposure100us);
  setControl(V4L2_CID_AUTOGAIN, 0);
  if (locked.gain) setControl(V4L2_CID_GAIN, *locked.gain);
  setControl(V4L2_CID_AUTO_WHITE_BALANCE, 0);
  if (locked.whiteBalanceK) setControl(V4L2_CID_WHITE_BALANCE_TEMPERATURE, *locked.whiteBalanceK);
  locked_ = true;
  lockedExposure_ = locked.exposure100us;
  lockedGain_ = locked.gain;
  return locked;
}

std::string V4l2Source::describe() const {
  return "camera " + settings_.device + " (" + card_ + ", " + fourccText(fourcc_) + " " +
         std::to_string(width_) + "x" + std::to_string(height_) + " @ " + formatFps(fps_) + ")";
}

CameraInfo queryCamera(const std::string& path) {
  UniqueFd fd(openV4l2Node(path));
  v4l2_capability cap{};
  if (v4l2Ioctl(fd.get(), VIDIOC_QUERYCAP, &cap) < 0)
    throw Error(path + ": not a V4L2 video device (VIDIOC_QUERYCAP: " + std::strerror(errno) + ")");
  CameraInfo info;
  info.path = path;
  info.card = reinterpret_cast<const char*>(cap.card);
  info.driver = reinterpret_cast<const char*>(cap.driver);
  info.bus = reinterpret_cast<const char*>(cap.bus_info);
  const std::uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
    info.videoCapture = false;
    info.kind = (caps & V4L2_CAP_META_CAPTURE)           ? "metadata"
                : (caps & V4L2_CAP_VIDEO_OUTPUT)         ? "video output"
                : (caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE) ? "multiplanar capture (not supported)"
                                                         : "not video capture";
    return info;
  }
  for (std::uint32_t i = 0;; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (v4l2Ioctl(fd.get(), VIDIOC_ENUM_FMT, &d) < 0) break;
    for (std::uint32_t j = 0;; ++j) {
      v4l2_frmsizeenum s{};
      s.index = j;
      s.pixel_format = d.pixelformat;
      if (v4l2Ioctl(fd.get(), VIDIOC_ENUM_FRAMESIZES, &s) < 0) break;
      CameraFrameSize m;
      m.fourcc = d.pixelformat;
      m.width = int(s.type == V4L2_FRMSIZE_TYPE_DISCRETE ? s.discrete.width : s.stepwise.max_width);
      m.height =
          int(s.type == V4L2_FRMSIZE_TYPE_DISCRETE ? s.discrete.height : s.stepwise.max_height);
      for (std::uint32_t k = 0;; ++k) {
        v4l2_frmivalenum iv{};
        iv.index = k;
        iv.pixel_format = d.pixelformat;
        iv.width = std::uint32_t(m.width);
        iv.height = std::uint32_t(m.height);
        if (v4l2Ioctl(fd.get(), VIDIOC_ENUM_FRAMEINTERVALS, &iv) < 0) break;
        if (iv.type == V4L2_FRMIVAL_TYPE_DISCRETE) {
          if (iv.discrete.numerator)
            m.fps.push_back(double(iv.discrete.denominator) / iv.discrete.numerator);
        } else {
          if (iv.stepwise.max.numerator)
            m.fps.push_back(double(iv.stepwise.max.denominator) / iv.stepwise.max.numerator);
          if (iv.stepwise.min.numerator)
            m.fps.push_back(double(iv.stepwise.min.denominator) / iv.stepwise.min.numerator);
          break;
        }
      }
      info.modes.push_back(m);
      if (s.type != V4L2_FRMSIZE_TYPE_DISCRETE) break;
    }
  }
  v4l2_queryctrl q{};
  q.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  while (v4l2Ioctl(fd.get(), VIDIOC_QUERYCTRL, &q) == 0) {
    if (!(q.flags & V4L2_CTRL_FLAG_DISABLED) && q.type != V4L2_CTRL_TYPE_CTRL_CLASS) {
      CameraControl c;
      c.id = q.id;
      c.name = reinterpret_cast<const char*>(q.name);
      c.type = int(q.type);
      c.minimum = q.minimum, c.maximum = q.maximum, c.step = q.step,
      c.defaultValue = q.default_value;
      v4l2_control v{};
      v.id = q.id;
      if (v4l2Ioctl(fd.get(), VIDIOC_G_CTRL, &v) == 0) c.value = v.value;
      info.controls.push_back(c);
    }
    q.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
  }
  return info;
}

void decodeCameraFrame(const CameraBuffer& in, int mjpegReduce, Frame& f) {
  cv::Mat bgr;
  auto* data = const_cast<std::uint8_t*>(in.data);  // cv::Mat wraps, never writes
  const std::size_t stride = in.bytesPerLine, rows = std::size_t(std::max(in.height, 0));
  // An uncompressed buffer must hold every row, each at least a row's worth of pixels.
  auto holds = [&](std::size_t pixelBytes, std::size_t planeRows) {
    return in.width > 0 && stride >= std::size_t(in.width) * pixelBytes &&
           in.bytes >= planeRows * stride;
  };
  try {
    switch (in.fourcc) {
      case V4L2_PIX_FMT_MJPEG:
      case V4L2_PIX_FMT_JPEG: {
        const int reduce = mjpegReduce >= 8 ? 8 : mjpegReduce >= 4 ? 4 : mjpegReduce >= 2 ? 2 : 1;
        // Only a JPEG (it starts with the SOI marker) of the negotiated size goes to the decoder.
        if (in.bytes < 2 || in.data[0] != 0xFF || in.data[1] != 0xD8 ||
            jpegFrameSize(in.data, in.bytes) != std::pair<int, int>{in.width, in.height})
          break;
        bgr = decodeCameraJpeg(in.data, in.bytes, reduce);
        // libjpeg's DCT scaling rounds up. A frame of any other size is not this stream's.
        if (!bgr.empty() && (bgr.cols != (in.width + reduce - 1) / reduce ||
                             bgr.rows != (in.height + reduce - 1) / reduce))
          bgr.release();
        break;
      }
      case V4L2_PIX_FMT_YUYV:
        // Y0 U Y1 V: two pixels share a macropixel, so a width must be even (OpenCV reads the
        // whole macropixel, past the row's end for an odd one).
        if (in.width % 2 == 0 && holds(2, rows))
          cv::cvtColor(cv::Mat(in.height, in.width, CV_8UC2, data, stride), bgr,
                       cv::COLOR_YUV2BGR_YUYV);
        break;
      case V4L2_PIX_FMT_NV12:
        if (holds(1, rows * 3 / 2))
          cv::cvtColor(cv::Mat(in.height * 3 / 2, in.width, CV_8UC1, data, stride), bgr,
                       cv::COLOR_YUV2BGR_NV12);
        break;
      case V4L2_PIX_FMT_RGB24:
        if (holds(3, rows))
          cv::cvtColor(cv::Mat(in.height, in.width, CV_8UC3, data, stride), bgr, cv::COLOR_RGB2BGR);
        break;
      default:
        break;
    }
  } catch (const cv::Exception&) {  // odd sizes the conversion refuses (NV12 needs even ones)
    bgr.release();
  }
  storeBgrFrame(bgr, f);  // empty: an empty frame, counted as dropped
}

}  // namespace lp
