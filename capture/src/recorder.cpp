#include "liveprobe/capture/recorder.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/videoio.hpp>

#include "liveprobe/capture/atomic_file.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/sh/error.h"

namespace lp {

namespace fs = std::filesystem;

struct VideoRecorder::Impl {
  cv::VideoWriter writer;
  int fourcc = 0;
  cv::Mat bgr;
};

VideoRecorder::VideoRecorder(std::string path, double fps, std::string sourceDescription)
    : impl_(std::make_unique<Impl>()),
      path_(std::move(path)),
      source_(std::move(sourceDescription)),
      fps_(fps > 0 ? fps : 30.0) {
  const fs::path p(path_);
  std::string ext = p.extension().string();
  for (auto& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".mkv")
    impl_->fourcc = cv::VideoWriter::fourcc('F', 'F', 'V', '1');
  else if (ext == ".avi")
    impl_->fourcc = cv::VideoWriter::fourcc('M', 'J', 'P', 'G');
  else if (ext == ".mp4")
    impl_->fourcc = cv::VideoWriter::fourcc('a', 'v', 'c', '1');  // H.264
  else
    throw Error(
        path_ +
        ": unsupported extension (expected .mkv: FFV1, lossless; .avi: MJPEG; .mp4: H.264)");
  video_ = std::make_unique<AtomicOutput>(path_);
  sidecar_ = std::make_unique<AtomicTextFile>(path_ + ".json");
}

VideoRecorder::~VideoRecorder() {
  try {
    discard();     // finish() was not called: the run failed, and nothing is put in place
  } catch (...) {  // a destructor must not throw; finish() already cleaned up what it could
  }
}

void VideoRecorder::write(const Frame& f) {
  if (finished_) throw Error(path_ + ": recording already finished");
  if (!stamps_.empty() && (f.width != width_ || f.height != height_)) {
    failed_ = true;  // a video has one frame size: this recording is discarded, not finalised
    throw Error(path_ + ": frame " + std::to_string(stamps_.size() + 1) + " is " +
                std::to_string(f.width) + "x" + std::to_string(f.height) + ", the recording is " +
                std::to_string(width_) + "x" + std::to_string(height_));
  }
  width_ = f.width;
  height_ = f.height;
  cv::Mat& bgr = impl_->bgr;
  double exposure = 0;
  if (f.format == PixelFormat::Bgr8) {
    exposure = 1.0 / f.radianceScale;  // the frame's own: a camera's may change every frame
    bgr = cv::Mat(f.height, f.width, CV_8UC3, const_cast<std::uint8_t*>(f.bgr8.data()));
  } else {
    if (exposure_ == 0) {
      // As a camera exposes: the 99.9th percentile of the pixels' largest channel at 95%, so a
      // sun's few pixels clip rather than push the sky into the lowest codes.
      std::vector<float> peaks(f.rgb.size() / 3);
      for (std::size_t i = 0; i < peaks.size(); ++i)
        peaks[i] = std::max(f.rgb[3 * i], std::max(f.rgb[3 * i + 1], f.rgb[3 * i + 2]));
      float level = 0;
      if (!peaks.empty()) {
        const auto at = peaks.begin() + std::ptrdiff_t(peaks.size() - 1 - peaks.size() / 1000);
        std::nth_element(peaks.begin(), at, peaks.end());
        level = *at;
      }
      exposure_ = level > 0 ? 0.95 / level : 1.0;
    }
    bgr.create(f.height, f.width, CV_8UC3);
    const float k = float(exposure_);
    for (int y = 0; y < f.height; ++y) {
      const float* s = f.rgb.data() + std::size_t(y) * f.width * 3;
      auto* d = bgr.ptr<std::uint8_t>(y);
      for (int x = 0; x < f.width; ++x, s += 3, d += 3)
        for (int c = 0; c < 3; ++c)
          d[2 - c] = std::uint8_t(std::lround(255.0f * linearToSrgb(s[c] * k)));
    }
    exposure = exposure_;
  }
  if (!impl_->writer.isOpened()) {
    if (!impl_->writer.open(video_->temporary(), cv::CAP_FFMPEG, impl_->fourcc, fps_,
                            cv::Size(f.width, f.height), true))
      throw Error(path_ + ": cannot open a video writer (this FFmpeg has no " +
                  (impl_->fourcc == cv::VideoWriter::fourcc('a', 'v', 'c', '1')
                       ? std::string("H.264")
                       : std::string("such")) +
                  " encoder)");
  }
  impl_->writer.write(bgr);
  stamps_.push_back(f.timestamp);
  exposures_.push_back(exposure);
}

void VideoRecorder::discard() {
  if (finished_) return;
  finished_ = true;
  impl_->writer.release();
  video_->discard();
  sidecar_.reset();  // its destructor removes the temporary
}

void VideoRecorder::finish() {
  if (failed_) {
    discard();
    throw Error(path_ + ": not written (a frame was refused)");
  }
  if (finished_) return;
  finished_ = true;
  if (!impl_->writer.isOpened()) {  // nothing was recorded: nothing is left behind
    video_->discard();
    return;
  }
  impl_->writer.release();
  // OpenCV's writer does not report FFmpeg's write errors (a full disk, a file size limit): the
  // finished video is opened again, and its container must account for every frame written.
  {
    cv::VideoCapture check;
    double count = -1;
    try {
      if (check.open(video_->temporary(), cv::CAP_FFMPEG))
        count = check.get(cv::CAP_PROP_FRAME_COUNT);
    } catch (const cv::Exception&) {
      count = -1;
    }
    if (std::abs(count - double(stamps_.size())) > 1) {
      video_->discard();
      sidecar_.reset();
      throw Error(path_ + ": the video was not written whole (" +
                  (count < 0 ? std::string("it cannot be read back")
                             : std::to_string(std::llround(count)) + " of " +
                                   std::to_string(stamps_.size()) + " frames") +
                  "); is the disk full?");
    }
  }
  nlohmann::ordered_json j;
  j["source"] = source_;
  j["fps"] = fps_;
  j["encoding"] = "srgb8";
  j["exposure"] = exposures_.empty() ? 1.0 : exposures_.front();  // older readers: one for all
  j["frames"] = stamps_.size();
  j["timestamps"] = stamps_;
  j["exposures"] = exposures_;
  sidecar_->line(j.dump());
  sidecar_->commit();  // the sidecar first: a video in place always has its timing beside it
  video_->commit();
}

RecordingSidecar parseRecordingSidecar(std::string_view text, const std::string& name) {
  RecordingSidecar out;
  try {
    const nlohmann::json j = nlohmann::json::parse(text);  // trailing text is an error
    // An exposure divides the frame: it must be positive, finite, and its inverse finite.
    auto scaleOf = [&](const nlohmann::json& e) {
      const double x = e.is_number() ? e.get<double>() : 0.0, s = 1.0 / x;
      if (!(x > 0) || !std::isfinite(x) || !std::isfinite(s))
        throw Error(name + ": exposure " + e.dump() + " is not a positive finite number");
      return s;
    };
    out.scale = scaleOf(j.at("exposure"));
    for (const auto& t : j.at("timestamps")) {
      const double s = t.get<double>();
      if (!std::isfinite(s)) throw Error(name + ": timestamp " + t.dump() + " is not finite");
      out.stamps.push_back(s);
    }
    // Recordings since the per-frame metadata keep every frame's exposure.
    if (j.contains("exposures"))
      for (const auto& e : j.at("exposures")) out.scales.push_back(scaleOf(e));
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(name + ": bad recording sidecar (" + e.what() + ")");
  }
  return out;
}

}  // namespace lp
