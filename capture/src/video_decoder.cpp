// libavcodec decoding to BGR8 frames (video_decoder.h).
#include "video_decoder.h"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <deque>
#include <utility>

#include "liveprobe/sh/error.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/imgutils.h>
#include <libswscale/swscale.h>
}

namespace lp {

namespace {

thread_local std::string tLastMessage;
void keepLastError(void*, int level, const char* format, va_list args) {
  if (level > AV_LOG_ERROR) return;
  char line[512];
  std::vsnprintf(line, sizeof line, format, args);
  std::string s = line;
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  if (!s.empty()) tLastMessage = s;
}

struct CodecFree {
  void operator()(AVCodecContext* c) const { avcodec_free_context(&c); }
};
struct PacketFree {
  void operator()(AVPacket* p) const { av_packet_free(&p); }
};
struct FrameFree {
  void operator()(AVFrame* f) const { av_frame_free(&f); }
};
struct SwsFree {
  void operator()(SwsContext* s) const { sws_freeContext(s); }
};

bool isKeyFrame(const AVFrame& f) {
#ifdef AV_FRAME_FLAG_KEY
  return (f.flags & AV_FRAME_FLAG_KEY) != 0;
#else
  return f.key_frame != 0;
#endif
}

}  // namespace

void keepFfmpegErrors() { av_log_set_callback(keepLastError); }
const std::string& lastFfmpegError() { return tLastMessage; }
void clearFfmpegError() { tLastMessage.clear(); }

std::string ffmpegErrorText(int code) {
  char b[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, b, sizeof b);
  return b;
}

struct VideoDecoder::Impl {
  std::unique_ptr<AVCodecContext, CodecFree> codec;
  std::unique_ptr<AVPacket, PacketFree> packet{av_packet_alloc()};
  std::unique_ptr<AVFrame, FrameFree> frame{av_frame_alloc()};
  std::unique_ptr<SwsContext, SwsFree> sws;
  std::string name;
  std::deque<std::pair<std::int64_t, double>> arrivals;  ///< packets sent: pts, arrival
  bool awaitKey = false;  ///< a packet was lost: frames withheld until a key frame

  void open(const AVCodec* c, const AVCodecParameters* params, bool lowDelay, bool noReorder) {
    keepFfmpegErrors();
    if (!c) throw Error("FFmpeg has no decoder for this stream");
    name = c->name;
    codec.reset(avcodec_alloc_context3(c));
    if (!codec || !packet || !frame ||
        (params && avcodec_parameters_to_context(codec.get(), params) < 0))
      throw Error("cannot set up the " + name + " decoder");
    if (lowDelay) {
      // A frame-threaded decoder holds a frame per thread back: slices only.
      if (noReorder) codec->flags |= AV_CODEC_FLAG_LOW_DELAY;
      codec->thread_type = FF_THREAD_SLICE;
    }
    codec->thread_count = 2;
    if (const int err = avcodec_open2(codec.get(), c, nullptr); err < 0)
      throw Error("cannot open the " + name + " decoder: " + ffmpegErrorText(err));
  }

  bool send(AVPacket* p, double arrival) {
    arrivals.emplace_back(p->pts, arrival);
    if (arrivals.size() > 64) arrivals.pop_front();  // a frame the decoder never gave
    if (avcodec_send_packet(codec.get(), p) != AVERROR_INVALIDDATA) return true;
    arrivals.pop_back();  // no frame will come of it: the caller counts it
    awaitKey = true;
    return false;
  }
};

VideoDecoder::VideoDecoder(const AVCodecParameters& stream, bool lowDelay)
    : d_(std::make_unique<Impl>()) {
  // A stream without B-frames is decoded without any delay; one with them keeps the reordering
  // it needs (forced out at once, its frames would come in decoding order), and each frame's
  // latency counts from its own packet's arrival, so the delay shows in the latency.
  d_->open(avcodec_find_decoder(stream.codec_id), &stream, lowDelay, stream.video_delay == 0);
}

VideoDecoder::VideoDecoder(const std::string& codec) : d_(std::make_unique<Impl>()) {
  d_->open(avcodec_find_decoder_by_name(codec.c_str()), nullptr, true, true);
}

VideoDecoder::~VideoDecoder() = default;

bool VideoDecoder::send(const AVPacket& packet, double arrival) {
  return d_->send(const_cast<AVPacket*>(&packet), arrival);  // avcodec_send_packet only reads it
}

bool VideoDecoder::send(const std::uint8_t* data, std::size_t bytes, std::int64_t pts,
                        double arrival) {
  AVPacket* p = d_->packet.get();
  if (av_new_packet(p, int(std::min<std::size_t>(bytes, 1 << 30))) < 0)
    throw Error("out of memory for a " + d_->name + " packet");
  std::copy_n(data, std::size_t(p->size), p->data);
  p->pts = p->dts = pts;
  const bool ok = d_->send(p, arrival);
  av_packet_unref(p);
  return ok;
}

void VideoDecoder::lost() { d_->awaitKey = true; }

void VideoDecoder::drain() { avcodec_send_packet(d_->codec.get(), nullptr); }

bool VideoDecoder::receive(Frame& f, Decoded& info, std::size_t& damaged) {
  Impl& d = *d_;
  for (;;) {
    const int err = avcodec_receive_frame(d.codec.get(), d.frame.get());
    if (err == AVERROR(EAGAIN) || err == AVERROR_EOF) return false;
    if (err < 0) throw Error("the " + d.name + " decoder failed: " + ffmpegErrorText(err));
    const AVFrame* in = d.frame.get();
    // Its own packet's arrival: a decoder that reorders gives it packets later. Frames come out
    // in presentation order, so a packet sent with an earlier pts that is still waiting is one
    // the decoder dropped (it had lost its reference): counted as damaged.
    info.arrival = -1;
    if (in->pts != AV_NOPTS_VALUE)
      for (auto a = d.arrivals.begin(); a != d.arrivals.end();) {
        if (a->first == in->pts && info.arrival < 0) {
          info.arrival = a->second;
        } else if (a->first == AV_NOPTS_VALUE || a->first >= in->pts) {
          ++a;
          continue;
        } else {
          ++damaged;
        }
        a = d.arrivals.erase(a);
      }
    if (d.awaitKey && isKeyFrame(*in)) d.awaitKey = false;
    if (d.awaitKey || in->decode_error_flags || (in->flags & AV_FRAME_FLAG_CORRUPT) ||
        in->width <= 0 || in->height <= 0) {
      ++damaged;
      av_frame_unref(d.frame.get());
      continue;
    }
    d.sws.reset(sws_getCachedContext(d.sws.release(), in->width, in->height,
                                     AVPixelFormat(in->format), in->width, in->height,
                                     AV_PIX_FMT_BGR24, SWS_BICUBIC, nullptr, nullptr, nullptr));
    if (!d.sws) throw Error("cannot convert the " + d.name + " decoder's pixel format");
    f.width = in->width;
    f.height = in->height;
    f.format = PanoramaFormat::BgrU8;
    f.rgb.clear();
    f.bgr8.resize(std::size_t(in->width) * std::size_t(in->height) * 3);
    f.radianceScale = 1.0;
    std::uint8_t* dst[4] = {f.bgr8.data(), nullptr, nullptr, nullptr};
    const int dstStride[4] = {in->width * 3, 0, 0, 0};
    sws_scale(d.sws.get(), in->data, in->linesize, 0, in->height, dst, dstStride);
    info.pts = in->best_effort_timestamp == AV_NOPTS_VALUE ? INT64_MIN : in->best_effort_timestamp;
    av_frame_unref(d.frame.get());
    return true;
  }
}

const std::string& VideoDecoder::name() const { return d_->name; }

}  // namespace lp
