#include "liveprobe/capture/atomic_file.h"

#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <utility>

#include "liveprobe/sh/error.h"

namespace lp {

namespace fs = std::filesystem;

namespace {

// The temporaries a signal handler may have to remove. A slot is claimed (free -> writing), its
// path written, then published (ready); the handler reads only ready slots. Releasing goes back
// through writing to free, so a handler never sees a path being rewritten as ready.
enum SlotState : int { kFree, kWriting, kReady };
struct TemporarySlot {
  std::atomic<int> state{kFree};
  char path[4096];
};
TemporarySlot gTemporaries[kMaxTemporaries];

int claimTemporary(const std::string& path) {
  if (path.size() >= sizeof(TemporarySlot::path)) return -1;
  for (int i = 0; i < kMaxTemporaries; ++i) {
    int expected = kFree;
    if (!gTemporaries[i].state.compare_exchange_strong(expected, kWriting)) continue;
    std::memcpy(gTemporaries[i].path, path.c_str(), path.size() + 1);
    gTemporaries[i].state.store(kReady, std::memory_order_release);
    return i;
  }
  return -1;
}

void releaseTemporary(int slot) {
  if (slot < 0) return;
  gTemporaries[slot].state.store(kWriting, std::memory_order_release);
  gTemporaries[slot].state.store(kFree, std::memory_order_release);
}

}  // namespace

void removeTemporariesNow() noexcept {
  for (TemporarySlot& t : gTemporaries)
    if (t.state.load(std::memory_order_acquire) == kReady) ::unlink(t.path);
}

AtomicOutput::AtomicOutput(std::string path) : path_(std::move(path)) {
  const fs::path p(path_);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw Error(path_ + ": folder " + dir.string() + " does not exist");
  if (fs::is_directory(p, ec)) throw Error(path_ + ": is a folder");
  // The longest name the folder's file system takes (NAME_MAX: 255 bytes on most).
  const long named = ::pathconf(dir.c_str(), _PC_NAME_MAX);
  const std::size_t nameMax = named > 0 ? std::size_t(named) : 255;
  const std::string name = p.filename().string(), ext = p.extension().string();
  if (name.size() > nameMax)
    throw Error(path_ + ": the file name is too long (" + std::to_string(name.size()) +
                " bytes; the file system takes " + std::to_string(nameMax) + ")");
  // The temporary: hidden, beside the target, its extension kept (encoders read it); the stem is
  // cut where the name would pass the limit, and a count keeps two such apart.
  static std::atomic<unsigned> made{0};
  const std::string tag = ".tmp" + std::to_string(::getpid()) + "-" + std::to_string(made++);
  std::string stem = p.stem().string();
  if (1 + stem.size() + tag.size() + ext.size() > nameMax)
    stem.resize(nameMax > 1 + tag.size() + ext.size() ? nameMax - 1 - tag.size() - ext.size() : 0);
  tmp_ = (dir / ("." + stem + tag + ext)).string();
  slot_ = claimTemporary(tmp_);
}

AtomicOutput::~AtomicOutput() { discard(); }

void AtomicOutput::discard() {
  if (done_) return;
  done_ = true;
  std::error_code ec;
  fs::remove(tmp_, ec);
  releaseTemporary(std::exchange(slot_, -1));
}

void AtomicOutput::commit() {
  if (done_) throw Error(path_ + ": already finished");
  std::error_code ec;
  fs::rename(tmp_, path_, ec);
  if (ec) {
    discard();
    throw Error(path_ + ": cannot rename into place (" + ec.message() + ")");
  }
  done_ = true;
  releaseTemporary(std::exchange(slot_, -1));
}

std::optional<std::uintmax_t> fileSizeLimit() {
  rlimit r{};
  if (::getrlimit(RLIMIT_FSIZE, &r) != 0 || r.rlim_cur == RLIM_INFINITY) return std::nullopt;
  return std::uintmax_t(r.rlim_cur);
}

std::string describeWriteError(int err) {
  if (err == ENOSPC) return "no space left on the device";
  if (err == EFBIG) {
    const auto limit = fileSizeLimit();
    return limit ? "file too large: the file-size limit (ulimit -f) is " + std::to_string(*limit) +
                       " bytes"
                 : "file too large for this file system";
  }
  return err ? std::strerror(err) : "write failed";
}

AtomicTextFile::AtomicTextFile(const std::string& path) : file_(path) {
  out_.open(file_.temporary(), std::ios::binary);
  if (!out_) throw Error(path + ": cannot write (" + describeWriteError(errno) + ")");
}

void AtomicTextFile::noteFault() {
  if (!out_ && fault_ == 0) fault_ = errno ? errno : EIO;
}

void AtomicTextFile::line(const std::string& s) {
  std::lock_guard lock(mutex_);
  errno = 0;
  out_ << s << '\n';
  noteFault();
}

void AtomicTextFile::write(const std::string& s) {
  std::lock_guard lock(mutex_);
  errno = 0;
  out_ << s;
  noteFault();
}

void AtomicTextFile::commit() {
  std::lock_guard lock(mutex_);
  errno = 0;
  out_.flush();
  noteFault();
  out_.close();
  noteFault();
  if (!out_ || fault_) {
    file_.discard();
    throw Error(file_.path() + ": cannot write (" + describeWriteError(fault_) + ")");
  }
  file_.commit();
}

void writeFileAtomically(const std::string& path, const std::string& text) {
  AtomicTextFile f(path);
  f.write(text);
  f.commit();
}

}  // namespace lp
