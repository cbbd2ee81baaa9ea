#pragma once
// Where a frame's record goes besides the screen: a coefficients log file, the WebSocket stream
// and an MQTT broker. Every sink takes each captured frame on capture's thread and never waits
// on its reader; a sink that wants the frame as drawn (a headless run's log keeps the render
// time) takes that too, on the render loop's thread.
#include <optional>
#include <string>

#include "liveprobe/exchange/engine_export.h"

namespace lp {

/// One captured frame and its record in the run's record format, serialized at most once
/// however many sinks take it as text.
class FrameRecord {
 public:
  FrameRecord(const ProcessedFrame& frame, const CoeffFormat& format)
      : frame_(frame), format_(format) {}
  const ProcessedFrame& frame() const { return frame_; }
  const std::string& text() {
    if (!text_) text_ = frameRecord(frame_, format_, {});
    return *text_;
  }

 private:
  const ProcessedFrame& frame_;
  const CoeffFormat& format_;
  std::optional<std::string> text_;
};

class RecordSink {
 public:
  virtual ~RecordSink() = default;
  /// Takes one frame's record (capture's thread; never waits for a reader).
  virtual void publish(FrameRecord& record) = 0;
  /// The frame as drawn, with its render time and latency (the render loop's thread; after its
  /// publish). Frames dropped before drawing never come here.
  virtual void shown(const ProcessedFrame& /*frame*/, RecordTimes /*times*/) {}
  /// One short line for the HUD ("stream: 2 clients, 0 dropped"); empty for none.
  virtual std::string status() const { return {}; }
  /// The run summary's line about this sink; empty for none.
  virtual std::string summary() const { return {}; }
  /// At the run's end (the stream closes its clients cleanly).
  virtual void stop() {}
  /// False when the sink failed its purpose over a run that captured frames (no message
  /// reached the broker): the run exits with an error.
  virtual bool delivered() const { return true; }
};

}  // namespace lp
