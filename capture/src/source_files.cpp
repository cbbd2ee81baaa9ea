// Sources backed by files: still images, cube-face sets, image sequences, video (OpenCV videoio
// with FFmpeg).
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/videoio.hpp>
#include <optional>

#include "liveprobe/backends.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/capture/network.h"
#include "liveprobe/capture/open_source.h"
#include "liveprobe/capture/recorder.h"
#include "liveprobe/frame/input_file.h"
#include "liveprobe/hdr/bracketed_source.h"
#include "liveprobe/sh/error.h"
#include "sources.h"

namespace lp {

namespace fs = std::filesystem;

namespace {

bool isImageFile(const fs::path& p) {
  static const std::array<std::string, 9> exts = {".hdr", ".exr", ".png",  ".jpg", ".jpeg",
                                                  ".pic", ".tif", ".tiff", ".bmp"};
  std::string e = p.extension().string();
  for (auto& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return std::find(exts.begin(), exts.end(), e) != exts.end();
}

// A fixed list of frames in memory or on disk, read one after another.
class ListSource : public FrameSource, public BracketedSource {
 public:
  ListSource(std::vector<std::string> files, double fps, std::string what)
      : files_(std::move(files)), fps_(fps), what_(std::move(what)) {}
  bool next(Frame& f) override {
    if (i_ >= files_.size()) return false;
    readImageFrame(files_[i_], f);
    if (i_ > 0 && (f.width != w_ || f.height != h_))
      throw Error(files_[i_] + ": frame size " + std::to_string(f.width) + "x" +
                  std::to_string(f.height) + " differs from the sequence's " + std::to_string(w_) +
                  "x" + std::to_string(h_));
    w_ = f.width, h_ = f.height;
    f.sequence = i_ < sidecar_.sequences.size() ? sidecar_.sequences[i_] : i_;
    f.timestamp = i_ < sidecar_.stamps.size() ? sidecar_.stamps[i_] : double(i_) / fps_;
    if (i_ < sidecar_.scales.size()) f.radianceScale = sidecar_.scales[i_];
    ++i_;
    return true;
  }
  /// A recording's sidecar (.png frames): each frame's time and exposure, its bracket.
  void setSidecar(RecordingSidecar sidecar) { sidecar_ = std::move(sidecar); }
  int bracketFrames() const override { return sidecar_.bracket; }
  std::string bracketResponse() const override { return sidecar_.response; }
  bool rewind() override {
    i_ = 0;
    return true;
  }
  std::string describe() const override { return what_; }
  double fps() const override { return fps_; }
  std::int64_t frameCount() const override { return std::int64_t(files_.size()); }

 private:
  std::vector<std::string> files_;
  double fps_;
  std::string what_;
  std::size_t i_ = 0;
  int w_ = 0, h_ = 0;
  RecordingSidecar sidecar_;
};

// Six face files assembled into a horizontal cross (liveprobe/sh/layout.h, cube).
class CubeFacesSource final : public FrameSource {
 public:
  CubeFacesSource(std::array<std::string, 6> faces, std::string dir, double fps)
      : faces_(std::move(faces)), dir_(std::move(dir)), fps_(fps) {}
  bool next(Frame& f) override {
    if (done_) return false;
    done_ = true;
    static const int cells[6][2] = {{2, 1}, {0, 1}, {1, 0},
                                    {1, 2}, {1, 1}, {3, 1}};  // px nx py ny pz nz
    int n = 0;
    for (int k = 0; k < 6; ++k) {
      const Image face = loadImage(faces_[k]);
      if (face.width != face.height) throw Error(faces_[k] + ": a cube face must be square");
      if (k == 0) {
        n = face.width;
        f.width = 4 * n, f.height = 3 * n;
        f.rgb.assign(std::size_t(f.width) * f.height * 3, 0.0f);
      } else if (face.width != n) {
        throw Error(faces_[k] + ": cube faces differ in size");
      }
      for (int y = 0; y < n; ++y)
        std::copy_n(
            face.pixel(0, y), std::size_t(n) * 3,
            f.rgb.data() +
                ((std::size_t(cells[k][1]) * n + y) * f.width + std::size_t(cells[k][0]) * n) * 3);
    }
    f.format = PanoramaFormat::RgbF32;
    f.bgr8.clear();
    f.sequence = 0;
    f.timestamp = 0;
    return true;
  }
  bool rewind() override {
    done_ = false;
    return true;
  }
  std::string describe() const override { return "cube faces in " + dir_; }
  double fps() const override { return fps_; }
  std::optional<Layout> layout() const override { return Layout::Cube; }
  std::int64_t frameCount() const override { return 1; }

 private:
  std::array<std::string, 6> faces_;
  std::string dir_;
  double fps_;
  bool done_ = false;
};

// A video file through OpenCV's FFmpeg backend. A frame that fails to decode in the middle is
// skipped and counted; after kMaxBadRun failures in a row the stream is over (a truncated file).
class VideoSource final : public FrameSource, public BracketedSource {
 public:
  explicit VideoSource(std::string path) : path_(std::move(path)) {
    open();
    // A recording made by `liveprobe record` carries a sidecar with its exposure and timestamps.
    std::error_code ec;
    if (fs::exists(path_ + ".json", ec)) {
      RecordingSidecar sc = parseRecordingSidecar(readInputFile(path_ + ".json"), path_ + ".json");
      scale_ = sc.scale;
      stamps_ = std::move(sc.stamps);
      scales_ = std::move(sc.scales);
      sequences_ = std::move(sc.sequences);
      bracket_ = sc.bracket;
      response_ = std::move(sc.response);
    }
  }
  int bracketFrames() const override { return bracket_; }
  std::string bracketResponse() const override { return response_; }
  bool next(Frame& f) override {
    cv::Mat m;
    int badRun = 0;
    for (;;) {
      bool ok = false;
      try {
        ok = cap_.read(m) && !m.empty();
      } catch (const cv::Exception&) {
        ok = false;
      }
      if (ok) break;
      // A frame FFmpeg cannot decode fails the read without advancing; reading on skips the
      // damage. A long run of failures is the end of the file (or of what survives of it).
      if (++badRun >= kMaxBadRun) {
        const double count = cap_.get(cv::CAP_PROP_FRAME_COUNT);
        if (count > 0 && double(read_ + skipped_) + 1 < count)
          endReason_ = "ended after " + std::to_string(read_) + " frames of " +
                       std::to_string(long(count)) + ": the rest does not decode (truncated file?)";
        return false;
      }
    }
    skipped_ +=
        std::size_t(read_ > 0 ? badRun : 0);  // failures before a good frame: skipped damage
    if (m.type() != CV_8UC3) throw Error(path_ + ": unsupported decoded pixel type");
    f.format = PanoramaFormat::BgrU8;
    f.width = m.cols, f.height = m.rows;
    f.rgb.clear();
    f.bgr8.resize(std::size_t(m.cols) * m.rows * 3);
    for (int y = 0; y < m.rows; ++y)
      std::copy_n(m.ptr<std::uint8_t>(y), std::size_t(m.cols) * 3,
                  f.bgr8.data() + y * std::size_t(m.cols) * 3);
    const auto index = std::uint64_t(std::max(0.0, cap_.get(cv::CAP_PROP_POS_FRAMES) - 1));
    f.sequence = index < sequences_.size() ? sequences_[index] : index;
    const double ms = cap_.get(cv::CAP_PROP_POS_MSEC);
    f.timestamp =
        index < stamps_.size() ? stamps_[index] : (ms > 0 ? ms / 1000.0 : double(index) / fps());
    f.radianceScale = index < scales_.size() ? scales_[index] : scale_;
    ++read_;
    return true;
  }
  bool rewind() override {
    cap_.release();
    open();
    read_ = 0;
    return true;
  }
  std::string describe() const override {
    return "video " + path_ + " (" + std::to_string(int(cap_.get(cv::CAP_PROP_FRAME_WIDTH))) + "x" +
           std::to_string(int(cap_.get(cv::CAP_PROP_FRAME_HEIGHT))) + ", " + formatFps(fps()) + ")";
  }
  double fps() const override {
    const double f = cap_.get(cv::CAP_PROP_FPS);
    return f > 0 && f < 1000 ? f : 30.0;
  }
  std::size_t skippedFrames() const override { return skipped_; }
  std::string endReason() const override { return endReason_; }
  std::int64_t frameCount() const override {  // the sidecar's, or the container's estimate
    if (!stamps_.empty()) return std::int64_t(stamps_.size());
    const double count = cap_.get(cv::CAP_PROP_FRAME_COUNT);
    return count >= 1 ? std::int64_t(count) : -1;
  }

 private:
  static constexpr int kMaxBadRun = 32;
  void open() {
    requireRegularFile(path_);
    if (!cap_.open(path_, cv::CAP_FFMPEG) || !cap_.isOpened())
      throw Error(path_ + ": cannot open as video (corrupt, truncated or unsupported codec)");
  }
  std::string path_;
  cv::VideoCapture cap_;
  std::size_t skipped_ = 0, read_ = 0;
  std::string endReason_;
  double scale_ = 1.0;
  std::vector<double> stamps_, scales_;
  std::vector<std::uint64_t> sequences_;  ///< the recording's frame numbers, where it keeps them
  int bracket_ = 0;
  std::string response_;
};

bool hasVideoExtension(const std::string& path) {
  std::string e = fs::path(path).extension().string();
  for (auto& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  for (const char* v : {".mp4", ".webm", ".mkv", ".avi", ".mov", ".m4v"})
    if (e == v) return true;
  return false;
}

}  // namespace

std::unique_ptr<FrameSource> openStill(const std::string& path, double fps) {
  return std::make_unique<ListSource>(std::vector<std::string>{path}, fps, "image " + path);
}

std::unique_ptr<FrameSource> openCubeFaces(const std::string& dir, double fps) {
  std::array<std::string, 6> faces;
  const char* names[6] = {"px", "nx", "py", "ny", "pz", "nz"};
  for (const auto& e : fs::directory_iterator(dir))
    for (int k = 0; k < 6; ++k)
      if (e.path().stem() == names[k] && isImageFile(e.path())) faces[k] = e.path().string();
  std::string found, missing;
  for (int k = 0; k < 6; ++k) (faces[k].empty() ? missing : found) += std::string(" ") + names[k];
  if (found.empty()) return nullptr;  // no face names: a plain sequence
  if (!missing.empty())
    throw Error(dir + ": a cube needs six faces; missing" + missing + " (found" + found + ")");
  return std::make_unique<CubeFacesSource>(faces, dir, fps);
}

std::string SequencePattern::at(int i) const {
  std::string n = std::to_string(i);
  if (int(n.size()) < width) n.insert(0, std::size_t(width) - n.size(), '0');
  return prefix + n + suffix;
}

std::optional<SequencePattern> parseSequencePattern(const std::string& spec) {
  const auto pos = spec.find('%');
  if (pos == std::string::npos) return std::nullopt;
  std::size_t i = pos + 1;
  int width = 0;
  if (i < spec.size() && spec[i] == '0') {
    ++i;
    if (i >= spec.size() || spec[i] < '1' || spec[i] > '9') return std::nullopt;
    width = spec[i++] - '0';
  }
  if (i >= spec.size() || spec[i] != 'd') return std::nullopt;
  if (spec.find('%', i + 1) != std::string::npos) return std::nullopt;
  return SequencePattern{spec.substr(0, pos), spec.substr(i + 1), width};
}

std::unique_ptr<ListSource> openSequence(const std::string& name, std::vector<std::string> files,
                                         double fps) {
  if (files.empty()) throw Error(name + ": no image files in this sequence");
  const std::string what =
      "image sequence " + name + " (" + std::to_string(files.size()) + " frames)";
  return std::make_unique<ListSource>(std::move(files), fps, what);
}

std::unique_ptr<FrameSource> openPatternSequence(const std::string& spec,
                                                 const SequencePattern& pattern, double fps) {
  std::vector<std::string> files;
  std::error_code ec;
  int i = 0;
  for (int misses = 0; misses < 2 && i < 10000000; ++i) {
    const std::string f = pattern.at(i);
    if (fs::is_regular_file(f, ec))
      files.push_back(f), misses = 0;
    else if (!files.empty() || i > 1)
      ++misses;  // numbering may start at 0 or 1
  }
  // Two misses in a row end the scan; a frame numbered beyond them means frames are missing,
  // which would otherwise end the replay early without a word.
  const fs::path dir = fs::path(pattern.at(0)).parent_path();
  long beyond = -1;
  for (const auto& e : fs::directory_iterator(dir.empty() ? fs::path(".") : dir, ec)) {
    const std::string name = dir.empty() ? e.path().filename().string() : e.path().string();
    if (name.size() <= pattern.prefix.size() + pattern.suffix.size() ||
        name.compare(0, pattern.prefix.size(), pattern.prefix) != 0 ||
        name.compare(name.size() - pattern.suffix.size(), pattern.suffix.size(), pattern.suffix))
      continue;
    const std::string digits = name.substr(
        pattern.prefix.size(), name.size() - pattern.prefix.size() - pattern.suffix.size());
    if (digits.size() > 9 ||
        !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    const long n = std::stol(digits);
    if (n >= i && (beyond < 0 || n < beyond)) beyond = n;
  }
  if (beyond >= 0 && !files.empty())
    throw Error(spec + ": " + pattern.at(i - 2) + " and " + pattern.at(i - 1) +
                " are missing, but the sequence goes on (" + pattern.at(int(beyond)) + ")");
  auto source = openSequence(spec, std::move(files), fps);
  // A recording of .png frames has its sidecar beside them, named after the pattern.
  if (fs::exists(spec + ".json", ec))
    source->setSidecar(parseRecordingSidecar(readInputFile(spec + ".json"), spec + ".json"));
  return source;
}

std::unique_ptr<FrameSource> openFolderSequence(const std::string& dir, double fps) {
  std::vector<std::string> files, recordings;
  for (const auto& e : fs::directory_iterator(dir)) {
    // A recording's sidecar, named after its frames' pattern (%04d.png.json): the folder
    // replays as that recording, with its exposures.
    const std::string name = e.path().filename().string();
    if (name.size() > 5 && name.compare(name.size() - 5, 5, ".json") == 0 &&
        parseSequencePattern(name.substr(0, name.size() - 5)))
      recordings.push_back(e.path().string());
    if (!isImageFile(e.path())) continue;
    std::error_code ec;
    const bool regular = e.is_regular_file(ec);
    if (ec)  // a link that loops or dangles, among the frames
      throw Error(e.path().string() + ": cannot read (" + ec.message() + ")");
    if (regular) files.push_back(e.path().string());
  }
  if (recordings.size() == 1) {
    const std::string spec = recordings[0].substr(0, recordings[0].size() - 5);
    return openPatternSequence(spec, *parseSequencePattern(spec), fps);
  }
  if (recordings.size() > 1)
    throw Error(dir + ": " + std::to_string(recordings.size()) +
                " recordings in one folder; replay one by its pattern, e.g. " +
                recordings[0].substr(0, recordings[0].size() - 5));
  std::sort(files.begin(), files.end());
  return openSequence(dir, std::move(files), fps);
}

std::unique_ptr<FrameSource> openVideo(const std::string& path) {
  return std::make_unique<VideoSource>(path);
}

// ":WxH[@FPS]" with every number in range; whole-string parses, so nothing wraps around.
bool parseSyntheticSpec(const std::string& rest, int& w, int& h, double& fps) {
  const char* p = rest.data();
  const char* end = p + rest.size();
  if (p == end || *p++ != ':') return false;
  auto r = std::from_chars(p, end, w);
  if (r.ec != std::errc() || r.ptr == end || *r.ptr != 'x') return false;
  r = std::from_chars(r.ptr + 1, end, h);
  if (r.ec != std::errc()) return false;
  if (r.ptr != end) {
    if (*r.ptr != '@') return false;
    r = std::from_chars(r.ptr + 1, end, fps);
    if (r.ec != std::errc() || r.ptr != end) return false;
  }
  return w >= 4 && h >= 2 && w <= 16384 && h <= 16384 && fps > 0 && fps <= 1000;
}

std::unique_ptr<FrameSource> openSource(const std::string& spec, const SourceOptions& options) {
  if (spec.rfind("synthetic", 0) == 0) {
    int w = 512, h = 256;
    double fps = 30;
    if (spec.size() > 9 && !parseSyntheticSpec(spec.substr(9), w, h, fps))
      throw Error(spec + ": expected synthetic[:WxH[@FPS]], W 4-16384, H 2-16384, FPS up to 1000");
    return openSynthetic(w, h, fps);
  }
  if (isNetworkUrl(spec)) {
#if LIVEPROBE_WITH_NETWORK
    NetworkSettings n;
    n.url = spec;
    n.mode = NetworkSettings::Mode::Every;
    n.timeoutMs = options.timeoutMs;
    return openNetwork(std::move(n));
#else
    throw Error(redactUrl(spec) +
                ": this liveprobe was built without network streams (LIVEPROBE_WITH_NETWORK)");
#endif
  }
  std::error_code ec;
  if (fs::is_directory(spec, ec)) {
    if (auto cube = openCubeFaces(spec, options.fps)) return cube;
    return openFolderSequence(spec, options.fps);
  }
  if (const auto pattern = parseSequencePattern(spec))
    return openPatternSequence(spec, *pattern, options.fps);
  if (hasVideoExtension(spec)) return openVideo(spec);
  requireRegularFile(spec);
  return openStill(spec, options.fps);
}

}  // namespace lp
