#include "liveprobe/capture/recorder.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/videoio.hpp>

#include "liveprobe/capture/atomic_file.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/capture/photometry.h"
#include "liveprobe/sh/error.h"
#include "sources.h"

namespace lp {

namespace fs = std::filesystem;

struct VideoRecorder::Impl {
  cv::VideoWriter writer;
  int fourcc = 0;
  cv::Mat bgr;
  // An image sequence: the frames go to a hidden folder beside them, renamed into place by
  // finish().
  std::optional<SequencePattern> pattern;
  fs::path partial;
  bool codes = false;     ///< .png frames: the camera's 8-bit codes, each exposure in the sidecar
  Linearizer linearizer;  ///< sRGB, for 8-bit frames
  Image image;
};

VideoRecorder::VideoRecorder(std::string path, double fps, std::string sourceDescription)
    : impl_(std::make_unique<Impl>()),
      path_(std::move(path)),
      source_(std::move(sourceDescription)),
      fps_(fps > 0 ? fps : 30.0) {
  auto lower = [](std::string e) {
    for (auto& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
    return e;
  };
  if (auto pattern = parseSequencePattern(path_)) {
    if (const auto slash = path_.rfind('/'); slash != std::string::npos && path_.find('%') < slash)
      throw Error(path_ + ": the frame-number pattern goes in the file name, not the folder");
    const auto dot = pattern->suffix.rfind('.');  // the suffix may be ".exr" alone
    const std::string ext = lower(dot == std::string::npos ? "" : pattern->suffix.substr(dot));
    if (ext != ".exr" && ext != ".hdr" && ext != ".png")
      throw Error(path_ +
                  ": an image-sequence recording keeps linear radiance in .exr or .hdr frames "
                  "(like frames/%04d.exr), or a camera's 8-bit codes in .png frames");
    impl_->codes = ext == ".png";
    const fs::path dir = fs::path(pattern->at(0)).parent_path();
    std::error_code ec;
    if (!dir.empty() && !fs::is_directory(dir, ec))
      throw Error(path_ + ": no folder " + dir.string() + " to record into");
    impl_->pattern = std::move(pattern);
    impl_->partial = (dir.empty() ? fs::path(".") : dir) /
                     (".liveprobe-recording." + std::to_string(::getpid()));
    if (impl_->codes) sidecar_ = std::make_unique<AtomicTextFile>(path_ + ".json");
    return;
  }
  const std::string ext = lower(fs::path(path_).extension().string());
  if (ext == ".exr" || ext == ".hdr")
    throw Error(path_ + ": " + ext + " frames need a frame-number pattern, like frames/%04d" + ext);
  if (ext == ".mkv")
    impl_->fourcc = cv::VideoWriter::fourcc('F', 'F', 'V', '1');
  else if (ext == ".avi")
    impl_->fourcc = cv::VideoWriter::fourcc('M', 'J', 'P', 'G');
  else if (ext == ".mp4")
    impl_->fourcc = cv::VideoWriter::fourcc('a', 'v', 'c', '1');  // H.264
  else
    throw Error(path_ +
                ": unsupported extension (expected .mkv: FFV1, lossless; .avi: MJPEG; .mp4: "
                "H.264; or an image-sequence pattern of .exr or .hdr frames, like "
                "frames/%04d.exr)");
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
  if (impl_->pattern) {
    writeSequenceFrame(f);
    return;
  }
  cv::Mat& bgr = impl_->bgr;
  double exposure = 0;
  if (f.format == PanoramaFormat::BgrU8) {
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
  sequences_.push_back(f.sequence);
  exposures_.push_back(exposure);
}

void VideoRecorder::writeSequenceFrame(const Frame& f) {
  if (impl_->codes && f.format != PanoramaFormat::BgrU8) {
    failed_ = true;
    throw Error(path_ + ": .png frames keep a camera's 8-bit codes; this stream is radiance: " +
                "record .exr frames (like frames/%04d.exr)");
  }
  std::error_code ec;
  if (stamps_.empty() && !fs::create_directory(impl_->partial, ec) && ec)
    throw Error(path_ + ": cannot create " + impl_->partial.string() + " (" + ec.message() + ")");
  // The frame is written in the hidden folder and moved into place at the end; a failure names
  // the file the user asked for, not the folder's.
  const std::string target = impl_->pattern->at(int(stamps_.size()));
  const std::string file = (impl_->partial / fs::path(target).filename()).string();
  const auto named = [&](const Error& e) {
    std::string what = e.what();
    if (what.rfind(file, 0) == 0) what.replace(0, file.size(), target);
    return Error(what);
  };
  if (impl_->codes) {
    // The codes as they came; the sidecar keeps each frame's exposure.
    try {
      saveImage8(file, f.width, f.height, 3, f.bgr8.data());
    } catch (const Error& e) {
      throw named(e);
    }
    stamps_.push_back(f.timestamp);
    sequences_.push_back(f.sequence);
    exposures_.push_back(1.0 / f.radianceScale);
    return;
  }
  // Linear radiance as the replay would see it: 8-bit frames decoded from sRGB, every frame
  // times its radiance scale, so the files need no exposure of their own.
  Image& img = impl_->image;
  impl_->linearizer.convert(f, img);
  if (f.radianceScale != 1.0)
    for (float& v : img.rgb) v *= float(f.radianceScale);
  try {
    saveImage(file, img, true);
  } catch (const Error& e) {
    throw named(e);
  }
  stamps_.push_back(f.timestamp);
  sequences_.push_back(f.sequence);
  exposures_.push_back(1.0);
}

void VideoRecorder::discard() {
  if (finished_) return;
  finished_ = true;
  if (impl_->pattern) {
    std::error_code ec;
    fs::remove_all(impl_->partial, ec);
    sidecar_.reset();
    return;
  }
  impl_->writer.release();
  video_->discard();
  sidecar_.reset();  // its destructor removes the temporary
}

void checkBracketRecording(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (auto& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  const bool sequence = parseSequencePattern(path).has_value();
  if ((sequence && ext == ".png") || (!sequence && ext == ".mkv")) return;
  throw Error(path + ": a bracket is recorded losslessly, each frame with its exposure: .mkv " +
              "(FFV1) or .png frames (like frames/%04d.png); " +
              (sequence ? ext + " frames keep radiance, not the codes the merge reads"
                        : ext + " is lossy"));
}

void VideoRecorder::setBracket(int frames, std::string responseJson) {
  checkBracketRecording(path_);
  bracket_ = frames;
  response_ = std::move(responseJson);
}

void VideoRecorder::finish() {
  if (failed_) {
    discard();
    throw Error(path_ + ": not written (a frame was refused)");
  }
  if (finished_) return;
  if (impl_->pattern) {
    finishSequence();
    return;
  }
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
                  "); " +
                  (fileSizeLimit() ? "is the disk full, or the file-size limit (ulimit -f) of " +
                                         std::to_string(*fileSizeLimit()) + " bytes reached?"
                                   : std::string("is the disk full?")));
    }
  }
  writeSidecar();  // the sidecar first: a video in place always has its timing beside it
  video_->commit();
}

void VideoRecorder::writeSidecar() {
  nlohmann::ordered_json j;
  j["source"] = source_;
  j["fps"] = fps_;
  j["encoding"] = "srgb8";
  j["exposure"] = exposures_.empty() ? 1.0 : exposures_.front();  // older readers: one for all
  j["frames"] = stamps_.size();
  j["timestamps"] = stamps_;
  j["exposures"] = exposures_;
  j["sequences"] = sequences_;
  if (bracket_ > 0) {
    j["bracket"] = bracket_;
    j["response"] = nlohmann::json::parse(response_).at("response");
  }
  sidecar_->line(j.dump());
  sidecar_->commit();
}

void VideoRecorder::finishSequence() {
  finished_ = true;
  const SequencePattern& pattern = *impl_->pattern;
  const int count = int(stamps_.size());
  std::error_code ec;
  // Every target is checked before the first rename: a folder or a device where a frame goes
  // fails the recording with nothing moved.
  for (int n = 0; n < count; ++n) {
    const fs::file_status st = fs::symlink_status(pattern.at(n), ec);
    if (fs::exists(st) && !fs::is_regular_file(st)) {
      fs::remove_all(impl_->partial, ec);
      throw Error(pattern.at(n) +
                  ": cannot put the recorded frame in place (something other "
                  "than a file is there)");
    }
  }
  // .png frames: their exposures and timing go in place before the frames.
  if (sidecar_ && count > 0) writeSidecar();
  sidecar_.reset();
  for (int n = 0; n < count; ++n) {
    fs::rename(impl_->partial / fs::path(pattern.at(n)).filename(), pattern.at(n), ec);
    if (ec) {
      const std::string why = ec.message();
      fs::remove_all(impl_->partial, ec);
      if (impl_->codes) fs::remove(path_ + ".json", ec);
      throw Error(pattern.at(n) + ": cannot put the recorded frame in place (" + why + ")");
    }
  }
  // The frames of an earlier, longer recording under the same pattern would replay after these:
  // those files go, up to the first name that is not a plain file (which is never touched).
  for (int n = count; fs::is_regular_file(fs::symlink_status(pattern.at(n), ec)); ++n)
    fs::remove(pattern.at(n), ec);
  fs::remove_all(impl_->partial, ec);
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
    // Recordings since the bracket's frame numbers keep every frame's.
    if (j.contains("sequences")) {
      for (const auto& q : j.at("sequences")) {
        if (!q.is_number_unsigned())
          throw Error(name + ": frame number " + q.dump() + " is not a whole number");
        out.sequences.push_back(q.get<std::uint64_t>());
      }
      if (out.sequences.size() != out.stamps.size())
        throw Error(name + ": " + std::to_string(out.sequences.size()) + " frame numbers for " +
                    std::to_string(out.stamps.size()) + " timestamps");
    }
    // Recordings since the per-frame metadata keep every frame's exposure.
    if (j.contains("exposures"))
      for (const auto& e : j.at("exposures")) out.scales.push_back(scaleOf(e));
    if (j.contains("bracket")) {
      out.bracket = j.at("bracket").get<int>();
      if (out.bracket < 1 || out.bracket > 5)
        throw Error(name + ": bracket " + j.at("bracket").dump() + " is not 1 to 5 frames");
      // The merge weighs each frame by its own exposure: a bracket keeps every frame's.
      if (out.scales.size() != out.stamps.size())
        throw Error(name + ": a bracket needs one exposure per frame (" +
                    std::to_string(out.scales.size()) + " exposures for " +
                    std::to_string(out.stamps.size()) + " timestamps)");
      if (j.contains("response"))
        out.response = nlohmann::json{{"response", j.at("response")}}.dump();
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(name + ": bad recording sidecar (" + e.what() + ")");
  }
  return out;
}

}  // namespace lp
