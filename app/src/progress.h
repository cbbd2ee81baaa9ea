#pragma once
// Progress of long runs, and clean stops. SIGINT, SIGTERM and SIGHUP set a flag that every long
// loop polls: the loop finishes or drops its current frame, the command finalises its outputs,
// prints its summary and exits with kExitInterrupted (kExitHangup for SIGHUP). main() installs
// the handlers before any other work, so a signal at any moment is that clean stop. A second
// signal ends the process at once, its unfinished outputs' temporaries removed first; a third
// changes nothing.
#include <chrono>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "liveprobe/capture/stages.h"

namespace lp::cli {

inline constexpr int kExitInterrupted = 130;  ///< 128 + SIGINT, as shells report it
inline constexpr int kExitHangup = 129;       ///< 128 + SIGHUP (the terminal closed)
inline constexpr int kExitInconclusive = 2;   ///< bench: a slower stage the machine's load explains
inline constexpr int kExitRuntime = 3;  ///< the run failed at run time (an internal error too)

/// Installs the SIGINT/SIGTERM/SIGHUP handlers (once; later calls do nothing).
void installStopHandlers();
/// The exit status of a run stopped by `sig`: kExitHangup for SIGHUP, else kExitInterrupted.
int exitStatusFor(int sig);

/// liveprobe's own error stream, on stderr. silenceLibraryStderr() points std::cerr nowhere, so
/// that a library's own line (OpenCV's "imread_(...)" before it returns its failure to us) never
/// joins the one line liveprobe prints about a bad input.
std::ostream& errs();
void silenceLibraryStderr();
/// A stop was asked for by a signal.
bool stopRequested();
/// The signal that asked for the stop (0 if none).
int stopSignal();

/// Frames done, rate and ETA on stderr: a bar redrawn in place on a terminal (at most 10 times a
/// second), a line every few seconds otherwise. Silent with quiet.
class Progress {
 public:
  /// total < 0: the end is unknown (no ETA).
  Progress(std::string what, std::int64_t total, bool quiet, std::string unit = "frames");
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void update(std::int64_t done);
  /// Clears the bar (terminal) so the summary starts on a clean line.
  void finish();

 private:
  using Clock = std::chrono::steady_clock;
  std::string what_, unit_;
  std::int64_t total_;
  bool quiet_, tty_, open_ = false;
  Clock::time_point start_, last_;
};

/// One warning line on stderr ("liveprobe: warning: ..."); the run goes on.
void warn(const std::string& text);

using lp::percentile;  // (liveprobe/capture/stages.h)

}  // namespace lp::cli
