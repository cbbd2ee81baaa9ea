// Network streams through FFmpeg (liveprobe/capture/network.h).
#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <cstdarg>
#include <cstdio>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include "camera_jpeg.h"
#include "liveprobe/capture/network.h"
#include "liveprobe/sh/error.h"
#include "video_decoder.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
}

namespace lp {

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// Every URL in free text (FFmpeg's own messages) redacted.
std::string scrubUrls(std::string text) {
  for (std::size_t at = text.find("://"); at != std::string::npos; at = text.find("://", at + 3)) {
    std::size_t begin = at;
    while (begin > 0 && std::isalpha(static_cast<unsigned char>(text[begin - 1]))) --begin;
    std::size_t end = at + 3;
    while (end < text.size() && !std::isspace(static_cast<unsigned char>(text[end])) &&
           text[end] != '\'' && text[end] != '"')
      ++end;
    const std::string clean = redactUrl(text.substr(begin, end - begin));
    text.replace(begin, end - begin, clean);
    at = begin + clean.size() - 3;
  }
  return text;
}

/// What a failed open or read means, for a person.
std::string whyFailed(int err, double timeoutSeconds) {
  if (err == AVERROR_EXIT || err == AVERROR(ETIMEDOUT))
    return "timed out (nothing within " + formatNumber(timeoutSeconds) + " s)";
  if (err == AVERROR(ECONNREFUSED)) return "connection refused";
  if (err == AVERROR_HTTP_NOT_FOUND || err == AVERROR(ENOENT)) return "not found";
  if (err == AVERROR_HTTP_UNAUTHORIZED || err == AVERROR_HTTP_FORBIDDEN)
    return "unauthorized (wrong or missing credentials)";
  if (err == AVERROR(EHOSTUNREACH) || err == AVERROR(ENETUNREACH)) return "host unreachable";
  if (err == AVERROR_EOF) return "the stream ended";
  std::string why = ffmpegErrorText(err);
  if (!lastFfmpegError().empty()) why += " (" + scrubUrls(lastFfmpegError()) + ")";
  return why;
}

struct FormatClose {
  void operator()(AVFormatContext* f) const { avformat_close_input(&f); }
};
struct PacketFree {
  void operator()(AVPacket* p) const { av_packet_free(&p); }
};

/// A failure of the connection (as opposed to one frame's damage): `code` is FFmpeg's.
struct StreamError {
  int code;
  std::string why;
};

/// One connection: opened, read packet by packet, decoded to BGR8 frames. Every wait inside
/// FFmpeg ends at `deadline` (or when `stop` is set) through the interrupt callback.
class Connection {
 public:
  Connection(const NetworkSettings& s, const std::atomic<bool>& stop) : s_(s), stop_(stop) {
    static std::once_flag network;
    std::call_once(network, [] { avformat_network_init(); });  // TLS's global state, once
    keepFfmpegErrors();
    clearFfmpegError();
    AVFormatContext* raw = avformat_alloc_context();
    if (!raw) throw StreamError{AVERROR(ENOMEM), "out of memory"};
    raw->interrupt_callback = {&Connection::interrupted, this};
    AVDictionary* options = nullptr;
    const std::string scheme = lower(s.url.substr(0, s.url.find("://")));
    if (s.mode == NetworkSettings::Mode::Latest) {
      // Low latency: a second of analysis at most before the first frame, and no reordering
      // delay. (FFmpeg's "nobuffer" would also drop what the analysis read: an SRT stream then
      // fails at its first frame.)
      av_dict_set(&options, "flags", "low_delay", 0);
      av_dict_set(&options, "analyzeduration", "1000000", 0);
    }
    if (scheme == "rtsp" || scheme == "rtsps")
      av_dict_set(&options, "rtsp_transport", s.rtspUdp ? "udp" : "tcp", 0);
    if (scheme == "udp") av_dict_set(&options, "overrun_nonfatal", "1", 0);
    armDeadline();
    int err = avformat_open_input(&raw, s.url.c_str(), nullptr, &options);
    av_dict_free(&options);
    if (err < 0) throw StreamError{err, why(err)};  // raw is freed
    format_.reset(raw);
    armDeadline();
    if ((err = avformat_find_stream_info(raw, nullptr)) < 0) throw StreamError{err, why(err)};
    const AVCodec* codec = nullptr;
    stream_ = av_find_best_stream(raw, AVMEDIA_TYPE_VIDEO, -1, -1, &codec, 0);
    if (stream_ < 0 || !codec)
      throw StreamError{AVERROR_STREAM_NOT_FOUND, stream_ == AVERROR_DECODER_NOT_FOUND
                                                      ? "a video FFmpeg has no decoder for"
                                                      : "not a video (no video stream in it)"};
    const AVStream* st = raw->streams[stream_];
    mjpeg_ = st->codecpar->codec_id == AV_CODEC_ID_MJPEG;
    codecName_ = codec->name;
    // The stream's own rate; a motion-JPEG multipart stream has none (FFmpeg's 25 is a guess).
    const bool guessed = std::string(raw->iformat->name) == "mpjpeg";
    const AVRational rate = st->avg_frame_rate.num > 0 ? st->avg_frame_rate
                            : guessed                  ? AVRational{0, 1}
                                                       : st->r_frame_rate;
    fps_ = rate.num > 0 && rate.den > 0 ? av_q2d(rate) : 0.0;
    if (fps_ > 1000) fps_ = 0;  // a stream's timebase, not a frame rate
    frames_ = st->nb_frames > 0 ? std::int64_t(st->nb_frames) : -1;
    timeBase_ = av_q2d(st->time_base);
    if (!mjpeg_) {
      try {
        decoder_ =
            std::make_unique<VideoDecoder>(*st->codecpar, s.mode == NetworkSettings::Mode::Latest);
      } catch (const Error& e) {
        throw StreamError{AVERROR(EINVAL), e.what()};
      }
    }
    packet_.reset(av_packet_alloc());
    if (!packet_) throw StreamError{AVERROR(ENOMEM), "out of memory"};
    width_ = st->codecpar->width;
    height_ = st->codecpar->height;
  }

  /// The next decoded frame (bgr8, sequence and timestamp left to the caller); false at the end
  /// of the stream. A frame that does not decode is counted in `corrupt` and read past.
  bool read(Frame& f, std::atomic<std::size_t>& corrupt) {
    for (;;) {
      if (!mjpeg_ && receive(f, corrupt)) return true;
      if (ended_) return false;
      armDeadline();
      const int err = av_read_frame(format_.get(), packet_.get());
      if (err == AVERROR_EOF) {
        ended_ = true;
        if (!mjpeg_) decoder_->drain();  // what it holds comes out
        continue;
      }
      if (err < 0) throw StreamError{err, why(err)};
      arrival_ = monotonicSeconds();
      const bool ours = packet_->stream_index == stream_;
      if (ours && mjpeg_) {
        const bool ok = decodeJpeg(f);
        pts(f);
        av_packet_unref(packet_.get());
        if (ok) return true;
        ++corrupt;
        continue;
      }
      if (ours && !decoder_->send(*packet_, arrival_)) ++corrupt;
      av_packet_unref(packet_.get());
    }
  }

  std::string describe() const {
    return redactUrl(s_.url) + " (" + (mjpeg_ ? std::string("motion JPEG") : codecName_) + " " +
           std::to_string(width_) + "x" + std::to_string(height_) +
           (fps_ > 0 ? " at " + formatFps(fps_) : "") + ")";
  }
  double fps() const { return fps_; }
  std::int64_t frameCount() const { return frames_; }
  double arrival() const { return arrival_; }

 private:
  static int interrupted(void* self) {
    auto* c = static_cast<Connection*>(self);
    return c->stop_.load() || monotonicSeconds() > c->deadline_ ? 1 : 0;
  }
  void armDeadline() { deadline_ = monotonicSeconds() + timeoutSeconds(); }
  /// A failure past the deadline is the timeout, whatever code a protocol made of it (RTSP
  /// says "invalid data" for a reply that never came).
  std::string why(int err) const {
    return whyFailed(!stop_ && monotonicSeconds() > deadline_ ? AVERROR_EXIT : err,
                     timeoutSeconds());
  }
  double timeoutSeconds() const { return s_.timeoutMs / 1000.0; }

  bool decodeJpeg(Frame& f) {
    const int reduce = s_.mjpegReduce;
    const cv::Mat bgr = decodeCameraJpeg(packet_->data, std::size_t(packet_->size), reduce);
    if (bgr.empty()) return false;
    storeBgrFrame(bgr, f);
    f.radianceScale = 1.0;
    width_ = bgr.cols * std::max(reduce, 1);
    height_ = bgr.rows * std::max(reduce, 1);
    return true;
  }

  /// A frame the decoder has ready; its latency counts from its own packet's arrival.
  bool receive(Frame& f, std::atomic<std::size_t>& corrupt) {
    VideoDecoder::Decoded info;
    std::size_t damaged = 0;
    bool got = false;
    try {
      got = decoder_->receive(f, info, damaged);
    } catch (const Error& e) {
      throw StreamError{AVERROR_INVALIDDATA, e.what()};
    }
    corrupt += damaged;
    if (!got) return false;
    width_ = f.width;
    height_ = f.height;
    f.timestamp = info.pts == INT64_MIN ? -1.0 : double(info.pts) * timeBase_;
    if (info.arrival >= 0) arrival_ = info.arrival;
    return true;
  }

  void pts(Frame& f) const {
    const std::int64_t t = packet_->pts != AV_NOPTS_VALUE ? packet_->pts : packet_->dts;
    f.timestamp = t == AV_NOPTS_VALUE ? -1.0 : double(t) * timeBase_;
  }

  const NetworkSettings& s_;
  const std::atomic<bool>& stop_;
  double deadline_ = 0;
  std::unique_ptr<AVFormatContext, FormatClose> format_;
  std::unique_ptr<VideoDecoder> decoder_;
  std::unique_ptr<AVPacket, PacketFree> packet_;
  int stream_ = -1;
  bool mjpeg_ = false, ended_ = false;
  std::string codecName_;
  double fps_ = 0, timeBase_ = 0, arrival_ = -1;
  std::int64_t frames_ = -1;
  int width_ = 0, height_ = 0;
};

/// The shared part of both modes: the connection, the frame numbering and the lines said.
class NetworkSource final : public FrameSource {
 public:
  explicit NetworkSource(NetworkSettings s) : s_(std::move(s)), shown_(redactUrl(s_.url)) {
    connection_ = connect();  // the first failure is the caller's error
    describe_ = connection_->describe();
    fps_ = connection_->fps();
    frames_ = connection_->frameCount();
    if (s_.mode == NetworkSettings::Mode::Latest) reader_ = std::thread([this] { readLoop(); });
  }
  ~NetworkSource() override {
    interrupt();
    if (reader_.joinable()) reader_.join();
  }

  bool next(Frame& f) override {
    if (s_.mode == NetworkSettings::Mode::Every) return readEvery(f);
    std::unique_lock lock(mutex_);
    for (;;) {
      if (slot_) {
        f = std::move(*slot_);
        slot_.reset();
        return true;
      }
      if (!fatal_.empty()) throw Error(fatal_);
      if (ended_ || stop_) return false;
      if (s_.interrupted && s_.interrupted()) {
        endReason_ = "stopped while waiting for " + shown_;
        return false;
      }
      cv_.wait_for(lock, std::chrono::milliseconds(50));
    }
  }
  bool rewind() override { return false; }
  std::string describe() const override { return describe_; }
  double fps() const override { return fps_; }
  std::size_t skippedFrames() const override { return corrupt_; }
  std::size_t staleFrames() const override { return dropped_; }
  std::string endReason() const override {
    std::lock_guard lock(mutex_);
    return endReason_;
  }
  std::int64_t frameCount() const override {
    return s_.mode == NetworkSettings::Mode::Every ? frames_ : -1;
  }
  std::size_t reconnects() const override { return reconnects_; }
  std::string waitingFor() const override {
    std::lock_guard lock(mutex_);
    if (lostAt_ < 0) return {};
    return "reconnecting for " + formatNumber(monotonicSeconds() - lostAt_, 2) +
           " s: " + (lastTry_.empty() ? lostWhy_ : lastTry_);
  }
  void interrupt() override {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
  }

 private:
  std::unique_ptr<Connection> connect() {
    try {
      return std::make_unique<Connection>(s_, stop_);
    } catch (const StreamError& e) {
      throw Error(shown_ + ": " + e.why);
    }
  }

  void number(Frame& f) {
    f.sequence = sequence_++;
    f.captureTime = connection_->arrival();
    if (first_ < 0) first_ = f.captureTime;
    f.exposure100us.reset();
    f.gain.reset();
    f.exposureReported = false;
  }

  bool readEvery(Frame& f) {
    try {
      if (!connection_->read(f, corrupt_)) return false;
    } catch (const StreamError& e) {
      endReason_ = "ended: " + e.why;
      return false;
    }
    const double pts = f.timestamp;
    number(f);
    if (pts >= 0 && firstPts_ < 0) firstPts_ = pts;
    f.timestamp = pts >= 0 ? pts - firstPts_ : f.captureTime - first_;
    return true;
  }

  // Latest: the reader thread. Decodes every frame (a codec's frames depend on each other) and
  // keeps the newest; a lost stream is reopened with a backoff, or ends the stream.
  void readLoop() {
    for (;;) {
      Frame f;
      std::string lost;
      try {
        if (connection_->read(f, corrupt_)) {
          number(f);
          f.timestamp = f.captureTime - first_;
          {
            std::lock_guard lock(mutex_);
            if (slot_) ++dropped_;
            slot_ = std::move(f);
          }
          cv_.notify_all();
          continue;
        }
        lost = "the stream ended";
      } catch (const StreamError& e) {
        lost = e.code == AVERROR_EXIT || e.why.rfind("timed out", 0) == 0
                   ? "no frame for " + formatNumber(s_.timeoutMs / 1000.0) + " s"
                   : "the connection dropped (" + e.why + ")";
      } catch (const std::exception& e) {  // out of memory, say: the run's error, not a crash
        std::lock_guard lock(mutex_);
        fatal_ = shown_ + ": " + e.what();
        cv_.notify_all();
        return;
      }
      if (stop_) return;
      if (!reconnect(lost)) return;
    }
  }

  /// Reopens the stream after `why`, waiting 0.25 s, then twice as long each try up to
  /// reconnectSeconds. False when the stream ends instead (reconnecting off, or a stop).
  bool reconnect(const std::string& why) {
    connection_.reset();
    if (s_.reconnectSeconds <= 0) {
      std::lock_guard lock(mutex_);
      if (why == "the stream ended") {
        ended_ = true;
        endReason_ = why;
      } else {
        fatal_ = shown_ + ": " + why;
      }
      cv_.notify_all();
      return false;
    }
    say(shown_ + ": " + why + "; reconnecting (waiting up to " + formatNumber(s_.reconnectSeconds) +
        " s between tries)");
    const double lostAt = monotonicSeconds();
    {
      std::lock_guard lock(mutex_);
      lostAt_ = lostAt;
      lostWhy_ = why;
      lastTry_.clear();
    }
    struct Back {  // waitingFor() says nothing once this try ends, whichever way
      NetworkSource& s;
      ~Back() {
        std::lock_guard lock(s.mutex_);
        s.lostAt_ = -1;
      }
    } back{*this};
    double wait = 0.25;
    for (int tries = 1;; ++tries) {
      {
        std::unique_lock lock(mutex_);
        if (cv_.wait_for(lock, std::chrono::duration<double>(wait), [&] { return stop_.load(); }))
          return false;
      }
      try {
        connection_ = std::make_unique<Connection>(s_, stop_);
        ++reconnects_;
        say(shown_ + ": reconnected after " + formatNumber(monotonicSeconds() - lostAt, 3) +
            " s (" + std::to_string(tries) + (tries == 1 ? " try" : " tries") + ")");
        return true;
      } catch (const StreamError& e) {
        if (stop_) return false;
        // Said again only when the reason changes: an hour's outage is not an hour of lines.
        if (e.why != lastTry_) say(shown_ + ": not back yet: " + e.why);
        std::lock_guard lock(mutex_);
        lastTry_ = e.why;
      }
      wait = std::min(wait * 2, s_.reconnectSeconds);
    }
  }

  void say(const std::string& line) const {
    if (s_.say) s_.say(line);
  }

  NetworkSettings s_;
  std::string shown_, describe_;
  std::atomic<bool> stop_{false};
  std::unique_ptr<Connection> connection_;
  std::thread reader_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::optional<Frame> slot_;
  bool ended_ = false;
  std::string fatal_, endReason_;
  std::string lastTry_, lostWhy_;  ///< while reconnecting: the last try's failure, the loss
  double lostAt_ = -1;             ///< while reconnecting: when the stream was lost
  std::uint64_t sequence_ = 0;
  double first_ = -1, firstPts_ = -1, fps_ = 0;
  std::int64_t frames_ = -1;
  std::atomic<std::size_t> corrupt_{0}, dropped_{0}, reconnects_{0};
};

}  // namespace

std::unique_ptr<FrameSource> openNetwork(NetworkSettings settings) {
  return std::make_unique<NetworkSource>(std::move(settings));
}

}  // namespace lp
