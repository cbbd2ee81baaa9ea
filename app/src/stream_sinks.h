#pragma once
// A stream's record sinks (liveprobe/exchange/record_sink.h), opened from the command line: the
// WebSocket stream (--serve), the MQTT broker (--publish) and the --coeffs-out file.
#include <memory>
#include <string>
#include <vector>

#include "hud.h"
#include "liveprobe/capture/atomic_file.h"
#include "liveprobe/exchange/engine_export.h"
#include "liveprobe/exchange/record_sink.h"
#include "settings.h"

namespace lp::cli {

struct RecordSinks {
  std::vector<std::unique_ptr<RecordSink>> all;
  /// What the sinks say about themselves (where the stream is served, a broker that does not
  /// answer), said once the source has given its first frame: a source that fails at once is
  /// its one line alone.
  std::vector<std::string> opening;

  /// Each sink's HUD line.
  void fill(HudCounters& c) const;
  /// The frame as drawn, to every sink.
  void shown(const ProcessedFrame& f, RecordTimes t) const;
};

/// --serve and --publish, as asked (lp::Error naming the option on a bad address, a missing
/// file, a backend this build lacks).
RecordSinks openSinks(const StreamSettings& st);

/// When --coeffs-out writes a frame's line.
enum class CoeffsLines {
  AtCapture,  ///< a window or a camera: as the frame is captured (no render time)
  AtDraw,     ///< headless replay: as it is drawn, with its render time and latency
};

/// Adds the --coeffs-out sink, writing `file` in `format`. AtDraw beside a network sink keeps
/// the records sent and not yet drawn, and writes them at stop(): a run stopped between capture
/// and drawing still logs every record that left the program (with render time null).
void addCoeffsSink(RecordSinks& sinks, AtomicTextFile& file, const CoeffFormat& format,
                   CoeffsLines when);

}  // namespace lp::cli
