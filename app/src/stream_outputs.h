#pragma once
// What a stream keeps besides its records: the rendered frames (--out-dir, --out-video), the raw
// stream (--record) and the --coeffs-out file. Each is finalised only when the run keeps it: a
// replay that fails part-way leaves no outputs.
#include <cstdint>
#include <glm/vec2.hpp>
#include <memory>
#include <string>
#include <vector>

#include "liveprobe/capture/atomic_file.h"
#include "liveprobe/capture/processed_frame.h"
#include "liveprobe/capture/recorder.h"
#include "liveprobe/exchange/engine_export.h"
#include "settings.h"

namespace lp::cli {

/// --out-dir: the frames this run wrote, removed again (with the folder, if the run made it)
/// unless the run kept them.
class FrameFolder {
 public:
  explicit FrameFolder(std::string dir);
  ~FrameFolder();
  FrameFolder(const FrameFolder&) = delete;
  FrameFolder& operator=(const FrameFolder&) = delete;

  /// DIR/frame_NNNNNN.png, from RGB bytes.
  void write(std::uint64_t index, glm::ivec2 size, const std::vector<std::uint8_t>& rgb);
  void keep() { kept_ = true; }

 private:
  std::string dir_;
  std::vector<std::string> written_;
  bool made_ = false, kept_ = false;
};

struct StreamOutputs {
  std::unique_ptr<AtomicTextFile> coeffs;  ///< --coeffs-out (its lines come from a record sink)
  CoeffFormat format;                      ///< --coeffs-format
  std::unique_ptr<FrameFolder> frames;
  std::unique_ptr<VideoRecorder> video, record;

  /// A rendered frame (RGB bytes of `size`) to --out-dir and --out-video.
  void writeFrame(const ProcessedFrame& f, glm::ivec2 size,
                  const std::vector<std::uint8_t>& rgb) const;
};

/// Opens what the options ask for (lp::Error naming the option).
StreamOutputs openOutputs(const Settings& s, double fps, const std::string& description);

}  // namespace lp::cli
