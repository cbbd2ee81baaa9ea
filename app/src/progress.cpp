#include "progress.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "liveprobe/capture/atomic_file.h"

namespace lp::cli {

namespace {

std::atomic<int> gStopSignal{0};

// The first signal sets the flag that every loop polls. The second ends the process at once,
// after removing the temporaries of the outputs not yet complete (unlink alone: signal-safe). The
// stop signals are blocked while the handler runs, so a third waits for that and changes nothing.
extern "C" void onStopSignal(int sig) {
  if (gStopSignal.exchange(sig) != 0) {
    lp::removeTemporariesNow();
    ::_exit(exitStatusFor(sig));
  }
}

std::string formatSeconds(double s) {
  char b[32];
  if (s < 100)
    std::snprintf(b, sizeof b, "%.0f s", s);
  else if (s < 6000)
    std::snprintf(b, sizeof b, "%.0f min %02.0f s", std::floor(s / 60),
                  s - 60 * std::floor(s / 60));
  else
    std::snprintf(b, sizeof b, "%.1f h", s / 3600);
  return b;
}

}  // namespace

void installStopHandlers() {
  static const bool once = [] {
    struct sigaction sa {};
    sa.sa_handler = onStopSignal;
    sigemptyset(&sa.sa_mask);
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&sa.sa_mask, sig);
    sa.sa_flags = 0;  // no SA_RESTART: a blocking read returns EINTR and the loop sees the flag
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);
    return true;
  }();
  (void)once;
}

int exitStatusFor(int sig) { return sig == SIGHUP ? kExitHangup : kExitInterrupted; }

std::ostream& errs() {
  static std::ostream out(std::cerr.rdbuf());
  static const bool once = [] {
    out.setf(std::ios::unitbuf);
    out.tie(&std::cout);
    return true;
  }();
  (void)once;
  return out;
}

void silenceLibraryStderr() {
  errs();  // bound to stderr's buffer first
  std::cerr.rdbuf(nullptr);
}

bool stopRequested() { return gStopSignal.load(std::memory_order_relaxed) != 0; }
int stopSignal() { return gStopSignal.load(); }

void warn(const std::string& text) {
  std::fprintf(stderr, "liveprobe: warning: %s\n", text.c_str());
}

Progress::Progress(std::string what, std::int64_t total, bool quiet, std::string unit)
    : what_(std::move(what)),
      unit_(std::move(unit)),
      total_(total),
      quiet_(quiet),
      tty_(::isatty(2) == 1),
      start_(Clock::now()),
      last_(start_) {}

Progress::~Progress() { finish(); }

void Progress::update(std::int64_t done) {
  if (quiet_) return;
  const auto now = Clock::now();
  const double sinceLast = std::chrono::duration<double>(now - last_).count();
  static const double lineEvery =
      [] {  // LIVEPROBE_PROGRESS_SECONDS: the interval between lines off a terminal
        const char* e = std::getenv("LIVEPROBE_PROGRESS_SECONDS");
        const double v = e ? std::atof(e) : 0.0;
        return v > 0 ? v : 5.0;
      }();
  if (sinceLast < (tty_ ? 0.1 : lineEvery)) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? double(done) / elapsed : 0;
  std::string text = what_ + ": " + std::to_string(done);
  if (total_ > 0) text += "/" + std::to_string(total_);
  char b[96];
  std::snprintf(b, sizeof b, " %s, %.1f/s", unit_.c_str(), rate);
  text += b;
  if (total_ > 0 && rate > 0 && done <= total_)
    text += ", ETA " + formatSeconds(double(total_ - done) / rate);
  else
    text += ", " + formatSeconds(elapsed);
  if (tty_) {
    std::string bar;
    if (total_ > 0) {
      const int width = 24,
                filled = int(width * std::min<double>(1.0, double(done) / double(total_)));
      bar = "[" + std::string(std::size_t(filled), '#') +
            std::string(std::size_t(width - filled), ' ') + "] ";
    }
    std::fprintf(stderr, "\r\033[K%s%s", bar.c_str(), text.c_str());
    open_ = true;
  } else {
    std::fprintf(stderr, "liveprobe %s\n", text.c_str());
  }
  std::fflush(stderr);
}

void Progress::finish() {
  if (open_) std::fprintf(stderr, "\r\033[K");
  open_ = false;
}

}  // namespace lp::cli
