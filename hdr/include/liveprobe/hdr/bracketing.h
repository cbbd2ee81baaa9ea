#pragma once
// Exposure bracketing of a camera: cycles its exposure time through a set of stops, one frame
// each, and names the exposure every frame was taken with, so that the merge
// (liveprobe/hdr/merge.h) can turn the codes into radiance.
//
// A camera applies a new exposure some frames after it is asked (its lag: the control delay and
// the buffers queued ahead) and then keeps it: frame s was taken with the exposure asked after
// frame s - lag. Once the lag is known, that schedule names every frame; what the camera reports
// (UVC metadata) or what the pixels measure (ExposureIdentifier: the frame's ratio to the frames
// known before it) confirms it, and does not decide it. So a scene that moves between frames,
// which shifts a pixel ratio by a few percent, never moves the exposure a frame is merged with;
// a frame the pixels measure nowhere near its scheduled exposure is left out, counted by stop;
// a frame they cannot measure (a hand over the lens, a stop that shares no well-exposed pixel
// with the known frames) is taken at its scheduled exposure, and the merge judges its pixels.
//
// The lag: the calibration's control delay where the response has one (confirmed by the first
// frames), else measured from the first frames: the smallest lag whose schedule explains every
// exposure reported or identified so far. A schedule that slips (a camera that changed its
// delay, a lost frame the sequence numbers do not show) is re-locked from the frames: when the
// last frames the pixels measured contradict it and another lag explains them. Nothing the scene
// does ends a run: only a camera that ignores its exposure control is refused, once, at start.
#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "liveprobe/frame/exposure_control.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/hdr/bracketed_source.h"
#include "liveprobe/hdr/merge.h"

namespace lp {

class ExposureIdentifier;

struct BracketOptions {
  std::vector<double> stops;  ///< stops from the locked exposure, 2 to kMaxBracket
  std::int32_t locked = 0;    ///< the locked exposure, 100 us
  CameraResponse response = CameraResponse::srgb();
  std::string name;  ///< the camera, as messages name it
  /// Told, once, what a user should know but that stops nothing (a lag other than the
  /// calibration's); unset: not told.
  std::function<void(const std::string&)> onWarning;
};

class Bracketing {
 public:
  /// The exposures asked, clamped to the control's range. Throws lp::Error as exposureRange().
  Bracketing(ExposureControl& control, BracketOptions options);
  ~Bracketing();
  Bracketing(const Bracketing&) = delete;
  Bracketing& operator=(const Bracketing&) = delete;

  /// The exposures of the cycle, in 100 us, in the order of the stops.
  const std::vector<std::int32_t>& asked() const { return asked_; }

  /// The anchor: a frame taken at the locked exposure, before the control moves, or at the one
  /// it reports (named so); asks for the cycle's first exposure.
  void start(Frame& anchor);
  /// Every frame the camera delivers after the anchor, in order: names the exposure it was
  /// taken with (Frame::radianceScale, Frame::exposure100us), and asks for the next exposure of
  /// the cycle. False: the frame is left out (its exposure is not known), and counted. Throws
  /// lp::Error when the camera shows it ignores its exposure control.
  bool take(Frame& frame);

  /// Frames left out, in all.
  std::size_t leftOut() const;
  /// What was left out, by stop and cause ("2 at -13 EV whose pixels contradicted the
  /// exposure asked"); empty when nothing was.
  std::string leftOutReport() const;
  /// The lag in force (frames from asking to the frame taken with it); none before it is known.
  std::optional<int> lag() const { return lag_; }

 private:
  struct Write {
    std::uint64_t after;  ///< the sequence number of the frame after which it was asked
    int stop;             ///< index into asked_
  };
  struct Seen {
    std::uint64_t sequence;
    double seconds;
  };
  /// The stop the schedule gives frame `sequence` at `lag` (-1: the locked exposure).
  int scheduled(std::uint64_t sequence, int lag) const;
  /// That stop's exposure time, seconds, as asked.
  double seconds(int stop) const;
  /// The stop whose exposure is nearest `measured` (seconds; -1: the locked one).
  int nearestStop(double measured) const;
  /// Whether `measured` names `stop`: no other exposure of the cycle, nor the locked one, is
  /// nearer.
  bool nearest(double measured, int stop) const;
  bool explains(int lag, const Seen& s) const;
  /// The smallest lag that explains the last `count` exposures seen (0: all of them).
  std::optional<int> explaining(std::size_t count) const;
  void lockLag();
  void relock();
  void setLag(int lag);
  void note(std::uint64_t sequence, double seconds);
  void askNext(std::uint64_t after);
  void name(Frame& frame, double seconds) const;
  void checkFollows(const Frame& frame);
  /// The first cycles' frames at the two shortest stops: where the shortest clips, told once.
  void watchClip(const Frame& frame);

  ExposureControl& control_;
  BracketOptions opt_;
  std::vector<std::int32_t> asked_;
  double base_ = 0;       ///< the locked exposure, seconds
  std::size_t next_ = 0;  ///< the cycle's next stop to ask
  std::deque<Write> writes_;
  std::deque<Seen> seen_;  ///< exposures reported or measured, newest last
  std::optional<int> lag_;
  bool warned_ = false;
  std::unique_ptr<ExposureIdentifier> identifier_;  ///< without reports: the pixels
  std::size_t taken_ = 0, run_ = 0;                 ///< frames taken; left out in a row
  double first_ = 0;                                ///< the first exposure seen (seconds)
  bool varied_ = false;                    ///< an exposure 2% or more from the first was seen
  std::vector<std::size_t> contradicted_;  ///< per stop (the last: the locked exposure)
  std::size_t unnamed_ = 0;                ///< before the lag was known: no exposure told
  std::int32_t least_ = 0;                 ///< the control's shortest exposure, 100 us
  /// Pixels clipped at the shortest and the next shorter exposure of the cycle, and how many
  /// frames of each were counted; the verdict is told once.
  std::array<std::size_t, 2> clipped_{}, clipSeen_{};
  bool clipTold_ = false;
};

/// A camera that brackets: its frames, each named with its exposure (frames whose exposure is
/// not known are left out). Owns the camera.
class BracketedCamera final : public FrameSource, public BracketedSource {
 public:
  /// `control` is the camera's own exposure control (the same object, or one it owns).
  BracketedCamera(std::unique_ptr<FrameSource> camera, ExposureControl& control,
                  BracketOptions options);
  /// Takes the anchor frame (the first next() delivers it) and starts the cycle. Throws
  /// lp::Error.
  void start();
  const Bracketing& bracketing() const { return bracketing_; }

  bool next(Frame& frame) override;
  bool rewind() override { return false; }
  std::string describe() const override { return camera_->describe(); }
  double fps() const override { return camera_->fps(); }
  std::size_t skippedFrames() const override { return camera_->skippedFrames(); }
  std::string endReason() const override { return camera_->endReason(); }
  int bracketFrames() const override { return int(bracketing_.asked().size()); }
  std::size_t unidentifiedFrames() const override { return bracketing_.leftOut(); }
  std::string unidentifiedReport() const override { return bracketing_.leftOutReport(); }

 private:
  std::unique_ptr<FrameSource> camera_;
  Bracketing bracketing_;
  std::unique_ptr<Frame> anchor_;  ///< the first frame, until it is delivered
};

}  // namespace lp
