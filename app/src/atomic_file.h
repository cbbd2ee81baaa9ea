#pragma once
// Output written under a temporary name beside the target and renamed into place only when
// complete, so an aborted or failed run leaves nothing half-written.
#include <fstream>
#include <mutex>
#include <string>

namespace lp::cli {

/// A text file written line by line (thread-safe) and renamed into place by commit(); its
/// temporary is removed if it is never committed.
class AtomicTextFile {
 public:
  /// Throws lp::Error when the folder does not exist or the temporary cannot be created.
  explicit AtomicTextFile(const std::string& path);
  ~AtomicTextFile();
  AtomicTextFile(const AtomicTextFile&) = delete;
  AtomicTextFile& operator=(const AtomicTextFile&) = delete;

  void line(const std::string& s);
  void write(const std::string& s);
  /// Flushes, closes and renames; throws lp::Error on any failure (and removes the temporary).
  void commit();
  const std::string& path() const { return path_; }

 private:
  std::string path_, tmp_;
  std::ofstream out_;
  std::mutex mutex_;
  bool committed_ = false;
};

/// The whole of `text` to `path`, atomically.
void writeFileAtomically(const std::string& path, const std::string& text);

}  // namespace lp::cli
