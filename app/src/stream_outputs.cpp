// --out-dir, --out-video, --record and the --coeffs-out file of a stream.
#include "stream_outputs.h"

#include <cstdio>
#include <filesystem>

#include "liveprobe/capture/image.h"
#include "liveprobe/sh/error.h"

namespace lp::cli {

namespace fs = std::filesystem;

FrameFolder::FrameFolder(std::string dir) : dir_(std::move(dir)) {
  std::error_code ec;
  made_ = !fs::exists(dir_, ec);
  if (!made_ && !fs::is_directory(dir_, ec))
    throw Error("--out-dir " + dir_ + ": is a file, not a folder");
  fs::create_directories(dir_, ec);
  if (!fs::is_directory(dir_, ec))
    throw Error("--out-dir " + dir_ + ": cannot create the folder (" + ec.message() + ")");
}

FrameFolder::~FrameFolder() {
  if (kept_) return;
  std::error_code ec;
  for (const auto& f : written_) fs::remove(f, ec);
  if (made_) fs::remove(dir_, ec);  // only if empty: nothing of anyone else's goes
}

void FrameFolder::write(std::uint64_t index, glm::ivec2 size,
                        const std::vector<std::uint8_t>& rgb) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%06llu.png", static_cast<unsigned long long>(index));
  const std::string path = (fs::path(dir_) / name).string();
  saveRgb8(path, size.x, size.y, rgb.data());
  written_.push_back(path);
}

void StreamOutputs::writeFrame(const ProcessedFrame& f, glm::ivec2 size,
                               const std::vector<std::uint8_t>& rgb) const {
  if (frames) frames->write(f.index, size, rgb);
  if (video) {
    Frame out;
    out.format = PanoramaFormat::BgrU8;
    out.width = size.x, out.height = size.y;
    out.timestamp = f.timestamp;
    out.bgr8.resize(rgb.size());
    for (std::size_t i = 0; i < rgb.size(); i += 3)
      out.bgr8[i] = rgb[i + 2], out.bgr8[i + 1] = rgb[i + 1], out.bgr8[i + 2] = rgb[i];
    video->write(out);
  }
}

StreamOutputs openOutputs(const Settings& s, double fps, const std::string& description) {
  const OutputSettings& os = s.output;
  StreamOutputs o;
  o.format = os.coeffsFormat;
  if (os.coeffsOut) o.coeffs = std::make_unique<AtomicTextFile>(*os.coeffsOut);
  if (os.outDir) o.frames = std::make_unique<FrameFolder>(*os.outDir);
  if (os.outVideo)
    o.video =
        std::make_unique<VideoRecorder>(*os.outVideo, fps, "liveprobe replay of " + description);
  if (s.stream.record)
    o.record = std::make_unique<VideoRecorder>(*s.stream.record, fps, description);
  return o;
}

}  // namespace lp::cli
