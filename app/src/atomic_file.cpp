#include "atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "liveprobe/sh/error.h"

namespace lp::cli {

namespace fs = std::filesystem;

AtomicTextFile::AtomicTextFile(const std::string& path) : path_(path) {
  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw Error(path + ": folder " + dir.string() + " does not exist");
  if (fs::is_directory(p, ec)) throw Error(path + ": is a folder");
  tmp_ = (dir / ("." + p.filename().string() + "." + std::to_string(::getpid()) + ".tmp")).string();
  out_.open(tmp_);
  if (!out_) throw Error(path + ": cannot write (" + std::strerror(errno) + ")");
}

AtomicTextFile::~AtomicTextFile() {
  if (!committed_) {
    out_.close();
    std::error_code ec;
    fs::remove(tmp_, ec);
  }
}

void AtomicTextFile::line(const std::string& s) {
  std::lock_guard lock(mutex_);
  out_ << s << '\n';
}

void AtomicTextFile::write(const std::string& s) {
  std::lock_guard lock(mutex_);
  out_ << s;
}

void AtomicTextFile::commit() {
  std::lock_guard lock(mutex_);
  out_.flush();
  out_.close();
  std::error_code ec;
  if (!out_) {
    fs::remove(tmp_, ec);
    throw Error(path_ + ": write failed (disk full?)");
  }
  fs::rename(tmp_, path_, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp_, ignored);
    throw Error(path_ + ": cannot rename into place: " + ec.message());
  }
  committed_ = true;
}

void writeFileAtomically(const std::string& path, const std::string& text) {
  AtomicTextFile f(path);
  f.write(text);
  f.commit();
}

}  // namespace lp::cli
