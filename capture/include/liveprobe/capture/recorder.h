#pragma once
// Recording a stream for later replay: FFV1 in .mkv (lossless) or MJPEG in .avi (near-lossless),
// through OpenCV videoio with FFmpeg, plus a JSON sidecar (FILE.json) with the exposure and every
// frame's timestamp. 8-bit frames are stored as they came; float (HDR) frames are stored as sRGB
// of radiance * exposure, the exposure chosen on the first frame so that 99.9% of its pixels are at
// or below 95% (a sun's few pixels clip, as on a camera).
// Or an image sequence (a frame-number pattern, like frames/%04d.exr: .exr frames as 16-bit
// floats, or .hdr), which keeps linear radiance whole, a sun included: frames numbered from 0,
// replayed at the rate the reader gives (no sidecar). Or .png frames (frames/%04d.png): a camera's
// 8-bit codes as they came, with a sidecar (frames/%04d.png.json) as a video's. The video is
// written under a temporary name and renamed, with its sidecar, only by finish() (a sequence's
// frames go to a hidden folder beside them first): a caller that keeps what was recorded up to a
// fault (a camera unplugged mid-stream) says so. Otherwise (an error, an exception) the destructor
// discards it, and so it does when a write was refused (a frame of another size): nothing half-made
// is ever put in place.
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "liveprobe/frame/frame.h"

namespace lp {

class AtomicOutput;
class AtomicTextFile;

class VideoRecorder {
 public:
  /// Throws lp::Error on an unsupported extension or an unwritable folder. 8-bit frames are
  /// stored as they came, each with its own exposure (1 / Frame::radianceScale) in the sidecar;
  /// in a sequence, every frame is linear radiance (8-bit frames decoded from sRGB).
  VideoRecorder(std::string path, double fps, std::string sourceDescription);
  ~VideoRecorder();
  VideoRecorder(const VideoRecorder&) = delete;
  VideoRecorder& operator=(const VideoRecorder&) = delete;

  /// Appends a frame (its timestamp goes to the sidecar). Throws lp::Error on a write failure.
  void write(const Frame& frame);
  /// The frames come in exposure brackets of `frames`, from a camera with this response
  /// (CameraResponse::json()): the sidecar says so, and a replay merges them as live did. Throws
  /// lp::Error where the recording could not replay the merge (checkBracketRecording).
  void setBracket(int frames, std::string responseJson);
  /// Closes the video, writes the sidecar, renames both into place. Idempotent. After a refused
  /// write it discards instead and throws lp::Error.
  void finish();
  /// Removes what was written; nothing is put in place. Idempotent.
  void discard();
  std::size_t frames() const { return stamps_.size(); }
  const std::string& path() const { return path_; }

 private:
  void writeSequenceFrame(const Frame& frame);
  void finishSequence();
  void writeSidecar();
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_, source_;
  std::unique_ptr<AtomicOutput> video_;      ///< the video under its temporary name
  std::unique_ptr<AtomicTextFile> sidecar_;  ///< FILE.json, likewise
  double fps_, exposure_ = 0;                ///< float frames: the one exposure chosen on the first
  std::vector<double> stamps_, exposures_;   ///< per frame
  std::vector<std::uint64_t> sequences_;     ///< per frame: Frame::sequence
  int width_ = 0, height_ = 0;
  int bracket_ = 0;
  std::string response_;
  bool finished_ = false, failed_ = false;  ///< failed: a write was refused; never finalised
};

/// A bracket replays as it ran only from its codes as they came, with each frame's exposure:
/// .mkv (FFV1) or .png frames. Throws lp::Error naming `path` for any other recording.
void checkBracketRecording(const std::string& path);

/// What a recording's sidecar (FILE.json) holds, as the replay reads it.
struct RecordingSidecar {
  double scale = 1.0;                  ///< radiance scale (1 / exposure) of every frame
  std::vector<double> stamps, scales;  ///< per frame; scales only in recordings that keep them
  /// Per frame, the source's own frame numbers (a camera's skip where frames were lost or left
  /// out of a bracket: the merge turns older frames by them); empty in older recordings.
  std::vector<std::uint64_t> sequences;
  int bracket = 0;       ///< frames per exposure bracket (0: not bracketed)
  std::string response;  ///< the bracket's camera response (CameraResponse::json())
};

/// Parses a sidecar's text (the whole of it: trailing text is an error). Exposures must be
/// positive and finite with a finite inverse, timestamps finite; a bracket of 1 to 5 frames with
/// one exposure per timestamp. Throws lp::Error naming `name`.
RecordingSidecar parseRecordingSidecar(std::string_view text, const std::string& name);

}  // namespace lp
