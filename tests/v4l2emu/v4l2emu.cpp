// An emulated V4L2 camera for tests, loaded with LD_PRELOAD into an unmodified liveprobe. It
// answers open/ioctl/mmap/munmap/poll/close on one device path and keeps the kernel's ioctl
// contract for what liveprobe uses (and what it must survive): QUERYCAP, ENUM_FMT,
// ENUM_FRAMESIZES, ENUM_FRAMEINTERVALS, G/S/TRY_FMT (S_FMT adjusts to the nearest offered mode),
// G/S_PARM, REQBUFS (count 0 frees; may grant fewer), QUERYBUF, QBUF, DQBUF (EAGAIN when empty),
// STREAMON, STREAMOFF (returns every buffer; streaming can start again), QUERYCTRL (NEXT_CTRL),
// G/S_CTRL. S_FMT and REQBUFS are EBUSY while buffers are allocated or mapped, as in vb2.
// The fd is a real eventfd, so the descriptor is genuine for close() and friends.
//
// Configuration (environment):
//   LPEMU_DEVICE   the path it answers (default /dev/video7)
//   LPEMU_SOURCE   a folder of modes: subfolders FOURCC_WxH (MJPG_640x320, YUYV_320x160, ...)
//                  holding the frames in name order (.jpg served verbatim for MJPG; other images
//                  converted to the mode's format; H264_ and HEVC_ modes encode them as a
//                  camera's encoder does, a key frame with its parameter sets every LPEMU_GOP
//                  frames (default 15), no B-frames, one access unit per buffer, and a frame the
//                  faults lose is lost from the stream: encoded, then not delivered). Float frames
//                  (.exr, .hdr) are radiance: each is rendered as an 8-bit sensor would see it,
//                  radiance x exposure time in force x gain / 64 x LPEMU_SENSITIVITY, through the
//                  response, clipped at 255; auto exposure then puts the frame's median luminance
//                  at mid-grey (0.18).
//   LPEMU_RESPONSE srgb (default) or gamma=G: the sensor's response for float sources
//   LPEMU_SENSITIVITY  float sources: sensor units per radiance x second (default 1)
//   LPEMU_META_DEVICE  a second path that answers as the camera's UVC metadata node: it streams
//                  V4L2_META_FMT_UVC (the standard payload header) or, once chosen with S_FMT,
//                  V4L2_META_FMT_UVC_MSXU_1_5 (the whole header, with Microsoft's capture
//                  statistics: the exposure time each frame was actually taken with)
//   LPEMU_FPS      frame rate (default 30)
//   LPEMU_GOP      H264_ and HEVC_ modes: frames from one key frame to the next (default 15)
//   LPEMU_FAULTS   comma list: busy_open, denied_open (EACCES), busy_reqbufs, grant=N, einval_fmt,
//   stop_after=N,
//                  eintr, unplug_after=N, exposure_walk (auto exposure changes every frame),
//                  refuse=ID (S_CTRL of that control id fails with EBUSY), latency=MS (each
//                  frame's timestamp is MS before its dequeue); faults that recur, for soak
//                  tests: corrupt_every=N (every Nth frame carries V4L2_BUF_FLAG_ERROR),
//                  garbage_every=N (every Nth frame is 1 byte of garbage), gap_every=N (the
//                  sequence skips a number every N frames: a frame lost before the reader);
//                  exposure: control_delay=N (a new exposure takes effect N frames after S_CTRL;
//                  G_CTRL reads the value written at once, as UVC's cache does),
//                  exposure_pow2 (the sensor applies the nearest power of two of what was asked),
//                  no_exposure (no V4L2_CID_EXPOSURE_ABSOLUTE), ignore_exposure (written values
//                  are taken and read back but never reach the sensor); occlusion: occlude_from=N,
//                  occlude_frames=K (default 10), occlude_white (white, not dark, frames);
//                  slow_fps=F (frames come at F a second while the mode says its own rate, as
//                  a camera's auto exposure does in dim light)
//   LPEMU_LOG      file to which each call, and each frame served with the exposure in force,
//                  is appended as one line (for assertions)
// What it cannot prove about real drivers: README, "Testing without a camera".
#include <dlfcn.h>
#include <fcntl.h>
#include <linux/uvcvideo.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../yuyv.h"

#if LPEMU_WITH_FFMPEG
extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/opt.h>
}
#endif

namespace fs = std::filesystem;

#ifndef V4L2_META_FMT_UVC_MSXU_1_5
#define V4L2_META_FMT_UVC_MSXU_1_5 v4l2_fourcc('U', 'V', 'C', 'M')
#endif

namespace {

template <class F>
F real(const char* name) {
  return reinterpret_cast<F>(dlsym(RTLD_NEXT, name));
}

std::string env(const char* k, const char* d = "") {
  const char* v = std::getenv(k);
  return v ? v : d;
}

struct Mode {
  std::uint32_t fourcc;
  int w, h;
  std::vector<std::string> files;
};

struct Control {
  std::uint32_t id;
  const char* name;
  v4l2_ctrl_type type;
  std::int32_t min, max, step, def, value;
};

// A metadata node's buffers (LPEMU_META_DEVICE), streamed beside the video's.
struct MetaNode {
  int fd = -1;
  std::uint32_t format = V4L2_META_FMT_UVC;
  std::vector<std::vector<std::uint8_t>> store;
  std::vector<void*> maps;
  std::vector<bool> queued, done;
  std::vector<std::uint32_t> used, sequence;
  bool streaming = false;
  static constexpr std::uint32_t kBufferSize = 10240;  // UVC_METADATA_BUF_SIZE
};

bool isVideoCodec(std::uint32_t fourcc) {
  return fourcc == V4L2_PIX_FMT_H264 || fourcc == V4L2_PIX_FMT_HEVC;
}

#if LPEMU_WITH_FFMPEG
// A camera's H.264 or HEVC encoder (libx264, libx265 through libavcodec): real time, no B-frames,
// parameter sets repeated with every key frame, Annex B output.
class Encoder {
 public:
  Encoder(std::uint32_t fourcc, int w, int h, double fps, int gop) {
    const bool h264 = fourcc == V4L2_PIX_FMT_H264;
    const AVCodec* codec = avcodec_find_encoder_by_name(h264 ? "libx264" : "libx265");
    if (!codec) return;
    av_log_set_level(AV_LOG_ERROR);  // the encoders' banners (FFmpeg's own printer only)
    ctx_ = avcodec_alloc_context3(codec);
    ctx_->width = w, ctx_->height = h;
    ctx_->pix_fmt = AV_PIX_FMT_YUV420P;
    ctx_->time_base = {1000, int(std::lround(fps * 1000))};
    ctx_->framerate = {int(std::lround(fps * 1000)), 1000};
    ctx_->gop_size = gop;
    ctx_->max_b_frames = 0;
    av_opt_set(ctx_->priv_data, "preset", "veryfast", 0);
    av_opt_set(ctx_->priv_data, "tune", "zerolatency", 0);
    av_opt_set(ctx_->priv_data, "crf", "18", 0);
    if (!h264) av_opt_set(ctx_->priv_data, "x265-params", "log-level=error:repeat-headers=1", 0);
    if (avcodec_open2(ctx_, codec, nullptr) < 0) avcodec_free_context(&ctx_);
    frame_ = av_frame_alloc();
    packet_ = av_packet_alloc();
  }
  ~Encoder() {
    avcodec_free_context(&ctx_);
    av_frame_free(&frame_);
    av_packet_free(&packet_);
  }
  bool ok() const { return ctx_ != nullptr; }
  // One frame in, its access unit out (zerolatency: nothing is held back). The sensor's BGR to
  // 4:2:0 as OpenCV converts it (BT.601, limited range).
  std::vector<std::uint8_t> encode(const cv::Mat& bgr) {
    std::vector<std::uint8_t> out;
    cv::Mat i420;
    cv::cvtColor(bgr, i420, cv::COLOR_BGR2YUV_I420);
    frame_->format = AV_PIX_FMT_YUV420P;
    frame_->width = ctx_->width, frame_->height = ctx_->height;
    const int w = ctx_->width, h = ctx_->height;
    std::uint8_t* planes[3] = {i420.data, i420.data + w * h, i420.data + w * h + w * h / 4};
    const int strides[3] = {w, w / 2, w / 2};
    for (int i = 0; i < 3; ++i) frame_->data[i] = planes[i], frame_->linesize[i] = strides[i];
    frame_->pts = pts_++;
    if (avcodec_send_frame(ctx_, frame_) < 0) return out;
    while (avcodec_receive_packet(ctx_, packet_) == 0) {
      out.insert(out.end(), packet_->data, packet_->data + packet_->size);
      av_packet_unref(packet_);
    }
    return out;
  }

 private:
  AVCodecContext* ctx_ = nullptr;
  AVFrame* frame_ = nullptr;
  AVPacket* packet_ = nullptr;
  std::int64_t pts_ = 0;
};
#endif

struct Emu {
  std::mutex m;
  int fd = -1;
  MetaNode metaNode;
  std::vector<Mode> modes;
  int mode = 0;
  double fps = 30;
  std::map<std::string, long> faults;
  std::vector<void*> maps;  // per buffer, the mapping handed out (nullptr if unmapped)
  std::vector<std::vector<std::uint8_t>> store;
  std::vector<bool> queued, done;
  std::vector<std::uint32_t> bytesused, seqOf;  // per buffer: bytes and sequence of its frame
  bool streaming = false, unplugged = false;
  std::uint32_t sequence = 0, served = 0;
  int frameIndex = 0;
  int eintrPoll = 0, eintrDq = 0;
  std::chrono::steady_clock::time_point nextFrame;
  std::vector<Control> controls = {
      {V4L2_CID_EXPOSURE_AUTO, "Auto Exposure", V4L2_CTRL_TYPE_MENU, 0, 3, 1, 3, 3},
      {V4L2_CID_EXPOSURE_ABSOLUTE, "Exposure Time, Absolute", V4L2_CTRL_TYPE_INTEGER, 1, 10000, 1,
       156, 156},
      {V4L2_CID_AUTOGAIN, "Gain, Automatic", V4L2_CTRL_TYPE_BOOLEAN, 0, 1, 1, 1, 1},
      {V4L2_CID_GAIN, "Gain", V4L2_CTRL_TYPE_INTEGER, 0, 255, 1, 64, 64},
      {V4L2_CID_AUTO_WHITE_BALANCE, "White Balance, Automatic", V4L2_CTRL_TYPE_BOOLEAN, 0, 1, 1, 1,
       1},
      {V4L2_CID_WHITE_BALANCE_TEMPERATURE, "White Balance Temperature", V4L2_CTRL_TYPE_INTEGER,
       2800, 6500, 10, 4600, 4600}};
  std::ofstream log;
  // The exposure the sensor integrates with (100 us units), and writes still on their way to it.
  int inForce = 156;
  std::deque<std::pair<std::uint32_t, int>> pendingExposure;  // (first frame, value)
  // Float sources: radiance per file, its median luminance, and the sensor's response.
  std::map<std::string, cv::Mat> radiance;
  std::map<std::string, double> medians;
  float responseGamma = 0;  // 0: sRGB
  double sensitivity = 1;
  std::string lastFile;
#if LPEMU_WITH_FFMPEG
  std::unique_ptr<Encoder> encoder;  // H264_ and HEVC_ modes: made at STREAMON (a new stream)
#endif

  Emu() {
    setenv("OPENCV_IO_ENABLE_OPENEXR", "1", 0);
    fps = std::atof(env("LPEMU_FPS", "30").c_str());
    sensitivity = std::atof(env("LPEMU_SENSITIVITY", "1").c_str());
    if (env("LPEMU_RESPONSE").rfind("gamma=", 0) == 0)
      responseGamma = float(std::atof(env("LPEMU_RESPONSE").c_str() + 6));
    std::stringstream fl(env("LPEMU_FAULTS"));
    for (std::string f; std::getline(fl, f, ',');) {
      const auto eq = f.find('=');
      faults[f.substr(0, eq)] = eq == std::string::npos ? 1 : std::atol(f.c_str() + eq + 1);
    }
    const std::string src = env("LPEMU_SOURCE");
    if (!src.empty() && fs::is_directory(src))
      for (const auto& d : fs::directory_iterator(src)) {
        const std::string n = d.path().filename().string();
        int w = 0, h = 0;
        char cc[5] = {};
        if (!d.is_directory() || std::sscanf(n.c_str(), "%4c_%dx%d", cc, &w, &h) != 3) continue;
        Mode md{v4l2_fourcc(cc[0], cc[1], cc[2], cc[3]), w, h, {}};
        for (const auto& f : fs::directory_iterator(d.path()))
          md.files.push_back(f.path().string());
        std::sort(md.files.begin(), md.files.end());
        if (!md.files.empty()) modes.push_back(md);
      }
    std::sort(modes.begin(), modes.end(), [](const Mode& a, const Mode& b) {
      return a.fourcc != b.fourcc ? a.fourcc < b.fourcc : a.w * a.h < b.w * b.h;
    });
    if (!env("LPEMU_LOG").empty()) log.open(env("LPEMU_LOG"), std::ios::app);
    if (fault("no_exposure"))
      controls.erase(
          std::remove_if(controls.begin(), controls.end(),
                         [](const Control& c) { return c.id == V4L2_CID_EXPOSURE_ABSOLUTE; }),
          controls.end());
  }
  bool fault(const char* k) const { return faults.count(k) > 0; }
  void say(const std::string& s) {
    if (log) log << s << std::endl;
  }
  Control* control(std::uint32_t id) {
    for (auto& c : controls)
      if (c.id == id) return &c;
    return nullptr;
  }
  std::uint32_t frameBytes(const Mode& md) const {
    if (md.fourcc == V4L2_PIX_FMT_YUYV) return std::uint32_t(md.w * md.h * 2);
    if (md.fourcc == V4L2_PIX_FMT_NV12) return std::uint32_t(md.w * md.h * 3 / 2);
    if (md.fourcc == V4L2_PIX_FMT_RGB24) return std::uint32_t(md.w * md.h * 3);
    return std::uint32_t(md.w * md.h * 3 + 65536);  // MJPEG: room for any JPEG of this size
  }

  // The next frame of the current mode, in its pixel format. Each is made once and kept, so a
  // long session opens no files (a soak test counts the process's descriptors).
  std::map<std::pair<int, std::string>, std::vector<std::uint8_t>> madeFrames;
  static bool isRadiance(const std::string& file) {
    return file.ends_with(".exr") || file.ends_with(".hdr");
  }
  // The next frame of the current mode, in its pixel format: a float source rendered with the
  // exposure in force; occlude_from: a hand over the lens.
  std::vector<std::uint8_t> rendered;
  const std::vector<std::uint8_t>& frameToServe() {
    const Mode& md = modes[std::size_t(mode)];
    const std::string& file = md.files[std::size_t(frameIndex++) % md.files.size()];
    lastFile = file;
    const long from = fault("occlude_from") ? faults["occlude_from"] : -1;
    const long count = fault("occlude_frames") ? faults["occlude_frames"] : 10;
    if (from >= 0 && long(served) >= from && long(served) < from + count) {
      cv::Mat flat(md.h, md.w, CV_8UC3, cv::Scalar::all(fault("occlude_white") ? 255 : 2));
      return rendered = encode(md, flat);
    }
    if (isRadiance(file)) return rendered = encode(md, sensor(md, file));
    if (isVideoCodec(md.fourcc)) {  // each frame depends on the ones before: encoded as served
      cv::Mat& bgr = madeImages[file];
      if (bgr.empty()) bgr = imageOf(md, file);
      return rendered = encode(md, bgr);
    }
    auto& made = madeFrames[{mode, file}];
    if (made.empty()) made = makeFrame(md, file);
    return made;
  }
  const cv::Mat& radianceOf(const Mode& md, const std::string& file) {
    cv::Mat& r = radiance[file];
    if (r.empty()) {
      r = cv::imread(file, cv::IMREAD_UNCHANGED);
      if (r.channels() == 4) cv::cvtColor(r, r, cv::COLOR_BGRA2BGR);
      r.convertTo(r, CV_32FC3);
      if (r.cols != md.w || r.rows != md.h) cv::resize(r, r, {md.w, md.h}, 0, 0, cv::INTER_AREA);
      std::vector<float> lum;
      for (int y = 0; y < r.rows; ++y)
        for (int x = 0; x < r.cols; ++x) {
          const auto& p = r.at<cv::Vec3f>(y, x);
          lum.push_back(0.2126f * p[2] + 0.7152f * p[1] + 0.0722f * p[0]);
        }
      std::nth_element(lum.begin(), lum.begin() + long(lum.size() / 2), lum.end());
      medians[file] = lum[lum.size() / 2];
    }
    return r;
  }
  double gainFactor() { return control(V4L2_CID_GAIN)->value / 64.0; }
  // What the sensor reads: radiance x exposure x gain x sensitivity, through the response.
  cv::Mat sensor(const Mode& md, const std::string& file) {
    const cv::Mat& r = radianceOf(md, file);
    const float k = float(inForce * 1e-4 * gainFactor() * sensitivity);
    cv::Mat out(r.rows, r.cols, CV_8UC3);
    for (int y = 0; y < r.rows; ++y)
      for (int x = 0; x < r.cols; ++x)
        for (int c = 0; c < 3; ++c) {
          const float v = std::clamp(r.at<cv::Vec3f>(y, x)[c] * k, 0.0f, 1.0f);
          const float e = responseGamma > 0 ? std::pow(v, 1.0f / responseGamma)
                          : v <= 0.0031308f ? 12.92f * v
                                            : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
          out.at<cv::Vec3b>(y, x)[c] = std::uint8_t(std::lround(255.0f * e));
        }
    return out;
  }
  // Auto exposure on a float source: the median luminance at mid-grey.
  int autoExposure(const std::string& file) {
    const double median = medians.count(file) ? medians[file] : 0.0;
    if (median <= 0) return 333;
    const double t = 0.18 / (median * gainFactor() * sensitivity);
    return int(std::clamp(std::lround(t / 1e-4), 1L, 10000L));
  }
  std::map<std::string, cv::Mat> madeImages;
  static cv::Mat imageOf(const Mode& md, const std::string& file) {
    cv::Mat bgr = cv::imread(file, cv::IMREAD_COLOR);
    if (bgr.cols != md.w || bgr.rows != md.h)
      cv::resize(bgr, bgr, {md.w, md.h}, 0, 0, cv::INTER_AREA);
    return bgr;
  }
  std::vector<std::uint8_t> makeFrame(const Mode& md, const std::string& file) {
    if (md.fourcc == V4L2_PIX_FMT_MJPEG && (file.ends_with(".jpg") || file.ends_with(".jpeg"))) {
      std::ifstream in(file, std::ios::binary);
      return std::vector<std::uint8_t>((std::istreambuf_iterator<char>(in)), {});
    }
    return encode(md, imageOf(md, file));
  }
  std::vector<std::uint8_t> encode(const Mode& md, const cv::Mat& bgr) {
    std::vector<std::uint8_t> out;
    if (isVideoCodec(md.fourcc)) {
#if LPEMU_WITH_FFMPEG
      if (!encoder) startEncoder();
      if (encoder->ok()) out = encoder->encode(bgr);
#endif
    } else if (md.fourcc == V4L2_PIX_FMT_MJPEG) {
      cv::imencode(".jpg", bgr, out, {cv::IMWRITE_JPEG_QUALITY, 95});
    } else if (md.fourcc == V4L2_PIX_FMT_RGB24) {
      cv::Mat rgb;
      cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
      out.assign(rgb.data, rgb.data + rgb.total() * 3);
    } else if (md.fourcc == V4L2_PIX_FMT_NV12) {
      cv::Mat i420;
      cv::cvtColor(bgr, i420, cv::COLOR_BGR2YUV_I420);
      const std::size_t ysz = std::size_t(md.w) * md.h, csz = ysz / 4;
      out.assign(i420.data, i420.data + ysz);
      for (std::size_t i = 0; i < csz; ++i)
        out.push_back(i420.data[ysz + i]), out.push_back(i420.data[ysz + csz + i]);
    } else {  // YUYV
      out = lpt::encodeYuyv(bgr);
    }
    return out;
  }

  int fail(int e) {
    errno = e;
    return -1;
  }
  // VIDIOC_QUERYCAP of one of the camera's nodes (both on one bus, as a UVC camera's are).
  static int capability(v4l2_capability* c, std::uint32_t kind) {
    *c = {};
    std::strcpy(reinterpret_cast<char*>(c->driver), "lpemu");
    std::strcpy(reinterpret_cast<char*>(c->card), "liveprobe emulated camera");
    std::strcpy(reinterpret_cast<char*>(c->bus_info), "platform:lpemu");
    c->version = 0x060100;
    c->device_caps = kind | V4L2_CAP_STREAMING;
    c->capabilities =
        V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_META_CAPTURE | V4L2_CAP_STREAMING | V4L2_CAP_DEVICE_CAPS;
    return 0;
  }

#if LPEMU_WITH_FFMPEG
  void startEncoder() {
    const Mode& md = modes[std::size_t(mode)];
    const long gop = std::atol(env("LPEMU_GOP", "15").c_str());
    encoder = std::make_unique<Encoder>(md.fourcc, md.w, md.h, fps, int(std::max(gop, 1L)));
  }
#endif
  // A frame the faults lose before the reader: a compressed stream loses its access unit.
  void loseFrame() {
#if LPEMU_WITH_FFMPEG
    if (isVideoCodec(modes[std::size_t(mode)].fourcc)) (void)frameToServe();
#endif
  }

  int handle(unsigned long req, void* arg);
  int handleMeta(unsigned long req, void* arg);
  void fillMeta(std::uint32_t seq);
};

// Never destroyed: munmap, close and poll still arrive after static destructors have run (from
// the C library at exit, and from a sanitizer's own reporting).
Emu& emu() {
  static Emu& e = *new Emu;
  return e;
}

int Emu::handle(unsigned long req, void* arg) {
  if (unplugged) return fail(ENODEV);
  switch (req) {
    case VIDIOC_QUERYCAP:
      // A UVC camera's second node carries metadata, not video.
      return capability(static_cast<v4l2_capability*>(arg), V4L2_CAP_VIDEO_CAPTURE);
    case VIDIOC_ENUM_FMT: {
      auto* d = static_cast<v4l2_fmtdesc*>(arg);
      std::vector<std::uint32_t> fcc;
      for (const auto& md : modes)
        if (std::find(fcc.begin(), fcc.end(), md.fourcc) == fcc.end()) fcc.push_back(md.fourcc);
      if (d->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || d->index >= fcc.size()) return fail(EINVAL);
      d->pixelformat = fcc[d->index];
      d->flags = d->pixelformat == V4L2_PIX_FMT_MJPEG || isVideoCodec(d->pixelformat)
                     ? V4L2_FMT_FLAG_COMPRESSED
                     : 0;
      std::snprintf(reinterpret_cast<char*>(d->description), sizeof d->description, "%.4s",
                    reinterpret_cast<char*>(&d->pixelformat));
      return 0;
    }
    case VIDIOC_ENUM_FRAMESIZES: {
      auto* s = static_cast<v4l2_frmsizeenum*>(arg);
      std::uint32_t n = 0;
      for (const auto& md : modes)
        if (md.fourcc == s->pixel_format && n++ == s->index) {
          s->type = V4L2_FRMSIZE_TYPE_DISCRETE;
          s->discrete = {std::uint32_t(md.w), std::uint32_t(md.h)};
          return 0;
        }
      return fail(EINVAL);
    }
    case VIDIOC_ENUM_FRAMEINTERVALS: {
      auto* iv = static_cast<v4l2_frmivalenum*>(arg);
      if (iv->index != 0) return fail(EINVAL);
      iv->type = V4L2_FRMIVAL_TYPE_DISCRETE;
      iv->discrete = {1000, std::uint32_t(fps * 1000)};
      return 0;
    }
    case VIDIOC_G_FMT:
    case VIDIOC_S_FMT:
    case VIDIOC_TRY_FMT: {
      auto* f = static_cast<v4l2_format*>(arg);
      if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      int pick = mode;
      if (req != VIDIOC_G_FMT) {
        // vb2_is_busy(): no format change while buffers are allocated (or streaming).
        if ((streaming || !store.empty()) && req == VIDIOC_S_FMT) return fail(EBUSY);
        // The nearest offered mode of the requested format; another format if it is not offered
        // (drivers adjust rather than fail) unless the einval_fmt fault is set.
        long best = -1;
        for (std::size_t i = 0; i < modes.size(); ++i) {
          if (modes[i].fourcc != f->fmt.pix.pixelformat) continue;
          const long d = std::labs(long(modes[i].w) - long(f->fmt.pix.width)) +
                         std::labs(long(modes[i].h) - long(f->fmt.pix.height));
          if (best < 0 || d < best) best = d, pick = int(i);
        }
        if (fault("einval_fmt") && req == VIDIOC_S_FMT) return fail(EINVAL);  // some drivers do
        if (req == VIDIOC_S_FMT) mode = pick, frameIndex = 0;
        say("S_FMT " + std::string(reinterpret_cast<char*>(&modes[std::size_t(pick)].fourcc), 4) +
            " " + std::to_string(modes[std::size_t(pick)].w) + "x" +
            std::to_string(modes[std::size_t(pick)].h));
      }
      const Mode& md = modes[std::size_t(pick)];
      f->fmt.pix.pixelformat = md.fourcc;
      f->fmt.pix.width = std::uint32_t(md.w);
      f->fmt.pix.height = std::uint32_t(md.h);
      f->fmt.pix.field = V4L2_FIELD_NONE;
      f->fmt.pix.bytesperline = md.fourcc == V4L2_PIX_FMT_YUYV    ? md.w * 2
                                : md.fourcc == V4L2_PIX_FMT_RGB24 ? md.w * 3
                                : md.fourcc == V4L2_PIX_FMT_NV12  ? md.w
                                                                  : 0;
      f->fmt.pix.sizeimage = frameBytes(md);
      f->fmt.pix.colorspace = V4L2_COLORSPACE_SRGB;
      return 0;
    }
    case VIDIOC_G_PARM:
    case VIDIOC_S_PARM: {
      auto* p = static_cast<v4l2_streamparm*>(arg);
      if (req == VIDIOC_S_PARM && p->parm.capture.timeperframe.numerator)
        fps = double(p->parm.capture.timeperframe.denominator) /
              p->parm.capture.timeperframe.numerator,
        say("S_PARM " + std::to_string(fps));
      p->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
      p->parm.capture.timeperframe = {1000, std::uint32_t(fps * 1000)};
      return 0;
    }
    case VIDIOC_REQBUFS: {
      auto* r = static_cast<v4l2_requestbuffers*>(arg);
      if (r->memory != V4L2_MEMORY_MMAP || r->type != V4L2_BUF_TYPE_VIDEO_CAPTURE)
        return fail(EINVAL);
      say("REQBUFS " + std::to_string(r->count));
      if (r->count == 0) {
        if (streaming) return fail(EBUSY);
        store.clear(), queued.clear(), done.clear(), bytesused.clear();
        return 0;
      }
      if (fault("busy_reqbufs")) return fail(EBUSY);
      // vb2_core_reqbufs(): not while streaming, nor while the old buffers are still mapped.
      if (streaming || std::any_of(maps.begin(), maps.end(), [](void* p) { return p; }))
        return fail(EBUSY);
      std::uint32_t n = std::min<std::uint32_t>(r->count, 8);
      if (fault("grant")) n = std::min<std::uint32_t>(n, std::uint32_t(faults["grant"]));
      r->count = n;
      store.assign(n, std::vector<std::uint8_t>(frameBytes(modes[std::size_t(mode)])));
      queued.assign(n, false), done.assign(n, false), bytesused.assign(n, 0), seqOf.assign(n, 0);
      maps.assign(n, nullptr);
      return 0;
    }
    case VIDIOC_QUERYBUF:
    case VIDIOC_QBUF:
    case VIDIOC_DQBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (b->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || b->memory != V4L2_MEMORY_MMAP)
        return fail(EINVAL);
      if (req == VIDIOC_DQBUF) {
        if (fault("eintr") && eintrDq++ % 7 == 3) return fail(EINTR);
        std::size_t i = 0;
        while (i < done.size() && !done[i]) ++i;
        if (i == done.size()) return fail(EAGAIN);
        done[i] = false;
        b->index = std::uint32_t(i);
        b->bytesused = bytesused[i];
        b->sequence = seqOf[i];
        // CLOCK_MONOTONIC, as the flag says (the kernel's contract for UVC). latency=MS: the
        // frame was exposed MS before it is dequeued (a slow sensor or USB transfer).
        timespec now{};
        clock_gettime(CLOCK_MONOTONIC, &now);
        if (fault("latency")) {
          const long long ns =
              now.tv_sec * 1000000000LL + now.tv_nsec - faults["latency"] * 1000000LL;
          now.tv_sec = ns / 1000000000LL;
          now.tv_nsec = ns % 1000000000LL;
        }
        b->timestamp.tv_sec = now.tv_sec;
        b->timestamp.tv_usec = now.tv_nsec / 1000;
        b->flags = V4L2_BUF_FLAG_MAPPED | V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
        if (fault("corrupt_every") && b->sequence % std::uint32_t(faults["corrupt_every"]) == 0)
          b->flags |= V4L2_BUF_FLAG_ERROR;  // the driver saw a damaged transfer
        b->length = std::uint32_t(store[i].size());
        return 0;
      }
      if (b->index >= store.size()) return fail(EINVAL);
      b->length = std::uint32_t(store[b->index].size());
      b->m.offset = b->index * 0x100000u;
      if (req == VIDIOC_QBUF) {
        if (queued[b->index]) return fail(EINVAL);
        queued[b->index] = true;
      }
      b->flags = V4L2_BUF_FLAG_MAPPED | (queued[b->index] ? V4L2_BUF_FLAG_QUEUED : 0);
      return 0;
    }
    case VIDIOC_STREAMON:
      if (store.empty()) return fail(EINVAL);
      streaming = true;
      nextFrame = std::chrono::steady_clock::now();
#if LPEMU_WITH_FFMPEG
      encoder.reset();  // a camera's new stream starts with a key frame
#endif
      say("STREAMON");
      return 0;
    case VIDIOC_STREAMOFF:
      streaming = false;
      std::fill(queued.begin(), queued.end(), false);
      std::fill(done.begin(), done.end(), false);
      say("STREAMOFF");
      return 0;
    case VIDIOC_QUERYCTRL: {
      auto* q = static_cast<v4l2_queryctrl*>(arg);
      const Control* c = nullptr;
      if (q->id & V4L2_CTRL_FLAG_NEXT_CTRL) {
        const std::uint32_t after = q->id & ~V4L2_CTRL_FLAG_NEXT_CTRL;
        for (const auto& x : controls)
          if (x.id > after && (!c || x.id < c->id)) c = &x;
      } else {
        c = control(q->id);
      }
      if (!c) return fail(EINVAL);
      *q = {};
      q->id = c->id, q->type = c->type, q->minimum = c->min, q->maximum = c->max, q->step = c->step;
      q->default_value = c->def;
      std::snprintf(reinterpret_cast<char*>(q->name), sizeof q->name, "%s", c->name);
      return 0;
    }
    case VIDIOC_G_CTRL:
    case VIDIOC_S_CTRL: {
      auto* v = static_cast<v4l2_control*>(arg);
      Control* c = control(v->id);
      if (!c) return fail(EINVAL);
      if (req == VIDIOC_G_CTRL) {
        v->value = c->value;
        return 0;
      }
      if (v->value < c->min || v->value > c->max) return fail(ERANGE);
      // Manual values are refused while the matching automatic mode is on (as UVC does).
      const bool blocked = (c->id == V4L2_CID_EXPOSURE_ABSOLUTE &&
                            control(V4L2_CID_EXPOSURE_AUTO)->value != V4L2_EXPOSURE_MANUAL) ||
                           (c->id == V4L2_CID_GAIN && control(V4L2_CID_AUTOGAIN)->value) ||
                           (c->id == V4L2_CID_WHITE_BALANCE_TEMPERATURE &&
                            control(V4L2_CID_AUTO_WHITE_BALANCE)->value);
      // refuse=ID: the camera refuses manual values of that control (EBUSY), as some firmware does.
      const bool refused = fault("refuse") && std::uint32_t(faults.at("refuse")) == c->id;
      say(std::string("S_CTRL ") + c->name + " " + std::to_string(v->value) +
          (blocked || refused ? " refused" : ""));
      if (blocked) return fail(EACCES);
      if (refused) return fail(EBUSY);
      c->value = v->value;
      if (c->id == V4L2_CID_EXPOSURE_ABSOLUTE && !fault("ignore_exposure")) {
        // The sensor takes it some frames later, and exposure_pow2 rounds it to a power of two.
        int applied = v->value;
        if (fault("exposure_pow2"))
          applied = 1 << int(std::lround(std::log2(std::max(1, applied))));
        pendingExposure.emplace_back(served + std::uint32_t(faults["control_delay"]), applied);
      }
      return 0;
    }
    default:
      return fail(ENOTTY);
  }
}

// The metadata node (LPEMU_META_DEVICE): the ioctls of a V4L2 metadata-capture node.
int Emu::handleMeta(unsigned long req, void* arg) {
  if (unplugged) return fail(ENODEV);
  MetaNode& n = metaNode;
  const auto type = V4L2_BUF_TYPE_META_CAPTURE;
  switch (req) {
    case VIDIOC_QUERYCAP:
      return capability(static_cast<v4l2_capability*>(arg), V4L2_CAP_META_CAPTURE);
    case VIDIOC_ENUM_FMT: {
      auto* d = static_cast<v4l2_fmtdesc*>(arg);
      const std::uint32_t offered[] = {V4L2_META_FMT_UVC, V4L2_META_FMT_UVC_MSXU_1_5};
      if (d->type != type || d->index >= 2) return fail(EINVAL);
      d->pixelformat = offered[d->index];
      d->flags = 0;
      std::snprintf(reinterpret_cast<char*>(d->description), sizeof d->description, "%.4s",
                    reinterpret_cast<char*>(&d->pixelformat));
      return 0;
    }
    case VIDIOC_G_FMT:
    case VIDIOC_S_FMT:
    case VIDIOC_TRY_FMT: {
      auto* f = static_cast<v4l2_format*>(arg);
      if (f->type != type) return fail(EINVAL);
      if (req == VIDIOC_S_FMT && (n.streaming || !n.store.empty())) return fail(EBUSY);
      std::uint32_t want = req == VIDIOC_G_FMT ? n.format : f->fmt.meta.dataformat;
      if (want != V4L2_META_FMT_UVC && want != V4L2_META_FMT_UVC_MSXU_1_5) want = V4L2_META_FMT_UVC;
      if (req == VIDIOC_S_FMT) n.format = want;
      f->fmt.meta.dataformat = want;
      f->fmt.meta.buffersize = MetaNode::kBufferSize;
      return 0;
    }
    case VIDIOC_REQBUFS: {
      auto* r = static_cast<v4l2_requestbuffers*>(arg);
      if (r->memory != V4L2_MEMORY_MMAP || r->type != type) return fail(EINVAL);
      if (n.streaming || std::any_of(n.maps.begin(), n.maps.end(), [](void* p) { return p; }))
        return fail(EBUSY);
      const std::uint32_t count = std::min<std::uint32_t>(r->count, 8);
      r->count = count;
      n.store.assign(count, std::vector<std::uint8_t>(MetaNode::kBufferSize));
      n.maps.assign(count, nullptr), n.queued.assign(count, false), n.done.assign(count, false);
      n.used.assign(count, 0), n.sequence.assign(count, 0);
      return 0;
    }
    case VIDIOC_QUERYBUF:
    case VIDIOC_QBUF:
    case VIDIOC_DQBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (b->type != type || b->memory != V4L2_MEMORY_MMAP) return fail(EINVAL);
      if (req == VIDIOC_DQBUF) {
        std::size_t i = 0;
        while (i < n.done.size() && !n.done[i]) ++i;
        if (i == n.done.size()) return fail(EAGAIN);
        n.done[i] = false;
        b->index = std::uint32_t(i);
        b->bytesused = n.used[i];
        b->sequence = n.sequence[i];
        b->flags = V4L2_BUF_FLAG_MAPPED | V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
        b->length = MetaNode::kBufferSize;
        return 0;
      }
      if (b->index >= n.store.size()) return fail(EINVAL);
      b->length = MetaNode::kBufferSize;
      b->m.offset = b->index * 0x100000u;
      if (req == VIDIOC_QBUF) {
        if (n.queued[b->index]) return fail(EINVAL);
        n.queued[b->index] = true;
      }
      b->flags = V4L2_BUF_FLAG_MAPPED | (n.queued[b->index] ? V4L2_BUF_FLAG_QUEUED : 0);
      return 0;
    }
    case VIDIOC_STREAMON:
      if (n.store.empty()) return fail(EINVAL);
      n.streaming = true;
      say("meta STREAMON");
      return 0;
    case VIDIOC_STREAMOFF:
      n.streaming = false;
      std::fill(n.queued.begin(), n.queued.end(), false);
      std::fill(n.done.begin(), n.done.end(), false);
      return 0;
    default:
      return fail(ENOTTY);
  }
}

// One uvc_meta_buf block for the frame with sequence `seq`: the payload header with PTS and SCR,
// then (V4L2_META_FMT_UVC_MSXU_1_5 only) Microsoft's capture statistics item with the exposure
// time in force, in 100 ns units (Microsoft's UVC 1.5 extensions, MetadataId_CaptureStats).
void Emu::fillMeta(std::uint32_t seq) {
  MetaNode& n = metaNode;
  if (!n.streaming) return;
  std::size_t i = 0;
  while (i < n.queued.size() && !n.queued[i]) ++i;
  if (i == n.queued.size()) return;  // the reader fell behind: this frame's block is lost
  std::vector<std::uint8_t> block(sizeof(uvc_meta_buf));
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  uvc_meta_buf head{};
  head.ns = std::uint64_t(now.tv_sec) * 1000000000ULL + std::uint64_t(now.tv_nsec);
  head.sof = std::uint16_t(seq & 0x7ff);
  head.flags = 0x80 | 0x08 | 0x04 | 0x02;    // end of header, SCR, PTS, end of frame
  std::vector<std::uint8_t> rest(4 + 6, 0);  // PTS, SCR
  if (n.format == V4L2_META_FMT_UVC_MSXU_1_5) {
    std::uint8_t stats[80] = {};
    const std::uint32_t id = 3, size = sizeof stats, flags = 1;  // EXPOSURETIME valid
    const std::uint64_t exposure100ns = std::uint64_t(inForce) * 1000;
    std::memcpy(stats, &id, 4), std::memcpy(stats + 4, &size, 4);
    std::memcpy(stats + 8, &flags, 4), std::memcpy(stats + 16, &exposure100ns, 8);
    rest.insert(rest.end(), stats, stats + sizeof stats);
  }
  head.length = std::uint8_t(2 + rest.size());
  std::memcpy(block.data(), &head, sizeof head);
  block.insert(block.end(), rest.begin(), rest.end());
  auto* dst = static_cast<std::uint8_t*>(n.maps[i]);
  if (dst) std::memcpy(dst, block.data(), block.size());
  n.used[i] = std::uint32_t(block.size());
  n.sequence[i] = seq;
  n.queued[i] = false;
  n.done[i] = true;
}

// Auto modes "converge" while frames flow: the values they settle on.
void settle(Emu& e) {
  // exposure_walk: auto exposure keeps adjusting, frame after frame (200..440 x 100 us).
  if (e.control(V4L2_CID_EXPOSURE_AUTO)->value != V4L2_EXPOSURE_MANUAL) {
    e.inForce = e.fault("exposure_walk")      ? 200 + 40 * int(e.served % 7)
                : Emu::isRadiance(e.lastFile) ? e.autoExposure(e.lastFile)
                                              : 333;
    if (Control* c = e.control(V4L2_CID_EXPOSURE_ABSOLUTE)) c->value = e.inForce;
  }
  if (e.control(V4L2_CID_AUTOGAIN)->value) e.control(V4L2_CID_GAIN)->value = 96;
  if (e.control(V4L2_CID_AUTO_WHITE_BALANCE)->value)
    e.control(V4L2_CID_WHITE_BALANCE_TEMPERATURE)->value = 5200;
}

int emuOpen(const char* path) {
  Emu& e = emu();
  std::lock_guard lock(e.m);
  e.say(std::string("open ") + path);
  if (e.fault("busy_open")) return e.fail(EBUSY);
  if (e.fault("denied_open")) return e.fail(EACCES);
  if (e.modes.empty()) return e.fail(ENODEV);
  int& fd = env("LPEMU_META_DEVICE") == path ? e.metaNode.fd : e.fd;
  if (fd >= 0) return e.fail(EBUSY);
  fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  return fd;
}

bool isDevice(const char* path) {
  return path && (env("LPEMU_DEVICE", "/dev/video7") == path ||
                  (!env("LPEMU_META_DEVICE").empty() && env("LPEMU_META_DEVICE") == path));
}
bool isFake(int fd) { return fd >= 0 && (fd == emu().fd || fd == emu().metaNode.fd); }

}  // namespace

extern "C" {

int open(const char* path, int flags, ...) {
  if (isDevice(path)) return emuOpen(path);
  va_list ap;
  va_start(ap, flags);
  const mode_t mode = (flags & (O_CREAT | O_TMPFILE)) ? mode_t(va_arg(ap, int)) : 0;
  va_end(ap);
  return real<int (*)(const char*, int, ...)>("open")(path, flags, mode);
}
int open64(const char* path, int flags, ...) {
  if (isDevice(path)) return emuOpen(path);
  va_list ap;
  va_start(ap, flags);
  const mode_t mode = (flags & (O_CREAT | O_TMPFILE)) ? mode_t(va_arg(ap, int)) : 0;
  va_end(ap);
  return real<int (*)(const char*, int, ...)>("open64")(path, flags, mode);
}
int openat(int dir, const char* path, int flags, ...) {
  if (isDevice(path)) return emuOpen(path);
  va_list ap;
  va_start(ap, flags);
  const mode_t mode = (flags & (O_CREAT | O_TMPFILE)) ? mode_t(va_arg(ap, int)) : 0;
  va_end(ap);
  return real<int (*)(int, const char*, int, ...)>("openat")(dir, path, flags, mode);
}
int __open_2(const char* path, int flags) {
  if (isDevice(path)) return emuOpen(path);
  return real<int (*)(const char*, int)>("__open_2")(path, flags);
}
int __open64_2(const char* path, int flags) {
  if (isDevice(path)) return emuOpen(path);
  return real<int (*)(const char*, int)>("__open64_2")(path, flags);
}

int close(int fd) {
  if (isFake(fd) && fd == emu().metaNode.fd) {
    Emu& e = emu();
    std::lock_guard lock(e.m);
    e.metaNode = MetaNode{};
  } else if (isFake(fd)) {
    Emu& e = emu();
    std::lock_guard lock(e.m);
    std::size_t mapped = 0;
    for (void* p : e.maps) mapped += p != nullptr;
    e.say("close mapped=" + std::to_string(mapped) + " buffers=" + std::to_string(e.store.size()) +
          " streaming=" + std::to_string(e.streaming));
    e.fd = -1;
    e.streaming = false;
  }
  return real<int (*)(int)>("close")(fd);
}

int ioctl(int fd, unsigned long req, ...) {
  va_list ap;
  va_start(ap, req);
  void* arg = va_arg(ap, void*);
  va_end(ap);
  if (!isFake(fd)) return real<int (*)(int, unsigned long, void*)>("ioctl")(fd, req, arg);
  Emu& e = emu();
  std::lock_guard lock(e.m);
  return fd == e.metaNode.fd ? e.handleMeta(req, arg) : e.handle(req, arg);
}

void* mmap(void* addr, size_t len, int prot, int flags, int fd, off_t off) {
  if (!isFake(fd))
    return real<void* (*)(void*, size_t, int, int, int, off_t)>("mmap")(addr, len, prot, flags, fd,
                                                                        off);
  Emu& e = emu();
  std::lock_guard lock(e.m);
  const bool meta = fd == e.metaNode.fd;
  auto& store = meta ? e.metaNode.store : e.store;
  const std::size_t i = std::size_t(off) / 0x100000u;
  if (i >= store.size() || len > store[i].size()) {
    errno = EINVAL;
    return MAP_FAILED;
  }
  void* p = real<void* (*)(void*, size_t, int, int, int, off_t)>("mmap")(
      nullptr, len, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  (meta ? e.metaNode.maps : e.maps)[i] = p;
  e.say("mmap " + std::to_string(i));
  return p;
}
void* mmap64(void* addr, size_t len, int prot, int flags, int fd, off_t off) {
  return mmap(addr, len, prot, flags, fd, off);
}

int munmap(void* addr, size_t len) {
  {
    Emu& e = emu();
    std::lock_guard lock(e.m);
    for (std::size_t i = 0; i < e.maps.size(); ++i)
      if (e.maps[i] == addr) {
        e.maps[i] = nullptr;
        e.say("munmap " + std::to_string(i));
      }
    for (void*& p : e.metaNode.maps)
      if (p == addr) p = nullptr;
  }
  return real<int (*)(void*, size_t)>("munmap")(addr, len);
}

int poll(struct pollfd* fds, nfds_t n, int timeout) {
  if (n != 1 || !isFake(fds[0].fd))
    return real<int (*)(struct pollfd*, nfds_t, int)>("poll")(fds, n, timeout);
  Emu& e = emu();
  std::unique_lock lock(e.m);
  fds[0].revents = 0;
  if (fds[0].fd == e.metaNode.fd) {  // the metadata node: ready when a block waits
    const bool ready =
        std::find(e.metaNode.done.begin(), e.metaNode.done.end(), true) != e.metaNode.done.end();
    if (ready) fds[0].revents = POLLIN | POLLRDNORM;
    return ready ? 1 : 0;
  }
  if (e.unplugged) {
    fds[0].revents = POLLERR;
    return 1;
  }
  if (e.fault("eintr") && e.eintrPoll++ % 5 == 2) return e.fail(EINTR);
  const bool stopped = e.fault("stop_after") && e.served >= std::uint32_t(e.faults["stop_after"]);
  const bool anyQueued = std::find(e.queued.begin(), e.queued.end(), true) != e.queued.end();
  if (!e.streaming || !anyQueued || stopped) {
    lock.unlock();
    std::this_thread::sleep_for(std::chrono::milliseconds(std::max(timeout, 0)));
    return 0;
  }
  // Pace frames at the configured rate.
  const auto due = e.nextFrame;
  lock.unlock();
  std::this_thread::sleep_until(due);
  lock.lock();
  e.nextFrame = std::max(due, std::chrono::steady_clock::now() - std::chrono::milliseconds(100)) +
                std::chrono::microseconds(
                    long(1e6 / (e.fault("slow_fps") ? double(e.faults["slow_fps"]) : e.fps)));
  if (e.fault("unplug_after") && e.served >= std::uint32_t(e.faults["unplug_after"])) {
    e.unplugged = true;
    e.say("unplug");
    fds[0].revents = POLLERR;
    return 1;
  }
  // Fill the first queued buffer with the next frame.
  for (std::size_t i = 0; i < e.queued.size(); ++i)
    if (e.queued[i]) {
      // The exposure the sensor has by now; the frame's sequence number (gap_every: the driver
      // lost a frame before this one, its number is skipped).
      while (!e.pendingExposure.empty() && e.pendingExposure.front().first <= e.served) {
        e.inForce = e.pendingExposure.front().second;
        e.pendingExposure.pop_front();
      }
      if (e.fault("gap_every") && (e.sequence + 1) % std::uint32_t(e.faults["gap_every"]) == 0)
        ++e.sequence, e.loseFrame();
      e.seqOf[i] = e.sequence++;
      e.say("frame " + std::to_string(e.seqOf[i]) + " exposure " + std::to_string(e.inForce));
      e.fillMeta(e.seqOf[i]);
      const auto& frame = e.frameToServe();
      auto* dst = static_cast<std::uint8_t*>(e.maps[i]);
      if (dst) std::memcpy(dst, frame.data(), std::min(frame.size(), e.store[i].size()));
      e.bytesused[i] = std::uint32_t(std::min(frame.size(), e.store[i].size()));
      // garbage_every: a frame the driver passes on without flagging it, one byte of zeros.
      if (e.fault("garbage_every") &&
          (e.served + 1) % std::uint32_t(e.faults["garbage_every"]) == 0) {
        if (dst) dst[0] = 0;
        e.bytesused[i] = 1;
      }
      e.queued[i] = false;
      e.done[i] = true;
      ++e.served;
      settle(e);
      break;
    }
  fds[0].revents = POLLIN | POLLRDNORM;
  return 1;
}

}  // extern "C"
