#include "liveprobe/bench/contention.h"

#include <filesystem>
#include <fstream>
#include <system_error>

namespace lp::bench {

Contention::Contention() : start_(read()) {}

double Contention::factor() const {
  double run = 0, wait = 0;
  for (const auto& [tid, now] : read()) {
    const auto was = start_.find(tid);
    const Times before = was == start_.end() ? Times{} : was->second;
    run += now.run - before.run, wait += now.wait - before.wait;
  }
  return run > 0 && wait > 0 ? 1.0 + wait / run : 1.0;
}

std::map<std::string, Contention::Times> Contention::read() {
  std::map<std::string, Times> out;
  std::error_code ec;
  for (const auto& t : std::filesystem::directory_iterator("/proc/self/task", ec)) {
    std::ifstream in(t.path() / "schedstat");
    Times v;
    if (in >> v.run >> v.wait) out[t.path().filename().string()] = v;
  }
  return out;
}

}  // namespace lp::bench
