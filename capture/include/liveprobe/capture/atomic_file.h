#pragma once
// The one way liveprobe writes output: under a temporary name beside the target, renamed into
// place only when complete, so an aborted or failed run leaves nothing half-written. Images,
// recordings and their sidecars, coefficient streams, bench reports and plots all go through it.
#include <cstdint>
#include <fstream>
#include <mutex>
#include <optional>
#include <string>

namespace lp {

/// A file made under a temporary name and renamed into place by commit(). The temporary is
/// ".STEM.tmpPID.EXT" in the target's folder: it keeps the extension, from which encoders (OpenCV,
/// FFmpeg) choose the format. Unless committed, the destructor removes it.
class AtomicOutput {
 public:
  /// Throws lp::Error when the folder does not exist or the target is a folder.
  explicit AtomicOutput(std::string path);
  ~AtomicOutput();
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;

  const std::string& path() const { return path_; }
  /// Where to write until commit().
  const std::string& temporary() const { return tmp_; }
  /// Renames the temporary into place; throws lp::Error (removing it) on failure.
  void commit();
  /// Removes the temporary now (idempotent).
  void discard();

 private:
  std::string path_, tmp_;
  bool done_ = false;
  int slot_ = -1;  ///< its place in removeTemporariesNow()'s table (-1: none)
};

/// A text file written line by line (thread-safe) through an AtomicOutput.
class AtomicTextFile {
 public:
  /// Throws lp::Error when the folder does not exist or the temporary cannot be created.
  explicit AtomicTextFile(const std::string& path);
  AtomicTextFile(const AtomicTextFile&) = delete;
  AtomicTextFile& operator=(const AtomicTextFile&) = delete;

  void line(const std::string& s);
  void write(const std::string& s);
  /// Flushes, closes and renames; throws lp::Error on any failure (and removes the temporary).
  void commit();
  const std::string& path() const { return file_.path(); }

 private:
  void noteFault();  ///< keeps errno of the first failed write (later calls overwrite it)

  AtomicOutput file_;
  std::ofstream out_;
  std::mutex mutex_;
  int fault_ = 0;
};

/// Removes every temporary of an AtomicOutput not yet committed or discarded, with unlink(2)
/// alone: async-signal-safe, for a signal handler that ends the process at once (a second
/// Ctrl-C) to leave nothing half-written behind. The temporaries are kept in a fixed table of
/// kMaxTemporaries paths; one beyond it is still removed by its owner, not by this.
void removeTemporariesNow() noexcept;
inline constexpr int kMaxTemporaries = 64;

/// The whole of `text` to `path`, atomically.
void writeFileAtomically(const std::string& path, const std::string& text);

/// The process's file-size limit in bytes (`ulimit -f`, RLIMIT_FSIZE), if it has one. liveprobe
/// ignores SIGXFSZ, so a write past it fails with EFBIG instead of killing the process.
std::optional<std::uintmax_t> fileSizeLimit();

/// A failed write's errno in the user's words ("no space left on the device", the size limit
/// named with its value); 0 when the writer did not say why.
std::string describeWriteError(int err);

}  // namespace lp
