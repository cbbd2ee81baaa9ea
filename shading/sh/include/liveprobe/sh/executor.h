#pragma once
// How parallelism enters the SH core: one small executor interface, and one way of splitting work
// over it (parallelFor, with parallelReduce on top). Projection, the brute-force integral and
// everything else in the core take an `Executor*` (nullptr: run on the calling thread). Bring
// your own (a job system, TBB, a GCD queue) by implementing run(); ThreadPool is the one the
// program uses.
#include <algorithm>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace lp {

class Executor {
 public:
  virtual ~Executor() = default;
  /// Threads that run tasks at once (the caller included); used to size the split.
  virtual unsigned concurrency() const = 0;
  /// Calls task(0), ..., task(tasks - 1), in any order and possibly at once, and returns when
  /// all have returned. Tasks must not throw.
  virtual void run(unsigned tasks, const std::function<void(unsigned)>& task) = 0;
};

/// A persistent pool: threads are created once, so a 30 us projection does not pay tens of
/// microseconds of thread start-up per frame. The calling thread works too.
class ThreadPool final : public Executor {
 public:
  /// `threads` in total, the caller included (1 = no workers, 0 = one per hardware thread). Throws
  /// lp::Error if the system cannot create them (the ones already made are joined first).
  explicit ThreadPool(unsigned threads);
  ~ThreadPool() override;
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  unsigned concurrency() const override { return unsigned(workers_.size()) + 1; }
  void run(unsigned tasks, const std::function<void(unsigned)>& task) override;

 private:
  void work();
  void stop();
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_, done_;
  const std::function<void(unsigned)>* fn_ = nullptr;
  unsigned tasks_ = 0, next_ = 0, finished_ = 0;
  std::uint64_t generation_ = 0;
  bool quit_ = false;
};

/// How [0, n) is cut: contiguous ranges whose starts are multiples of `grain` (so a kernel that
/// works in blocks of 16 can ask for grain 16), about `perThread` ranges per thread for balance,
/// and none longer than `maxChunk` (a small one keeps a progress callback responsive).
struct Split {
  std::size_t grain = 1;
  unsigned perThread = 4;
  std::size_t maxChunk = SIZE_MAX;
};

/// Calls body(begin, end) for consecutive ranges covering [0, n), on the executor's threads.
template <class Body>
void parallelFor(Executor* ex, std::size_t n, Split split, Body body) {
  if (n == 0) return;
  const std::size_t g = std::max<std::size_t>(1, split.grain);
  const std::size_t wanted = ex ? std::size_t(ex->concurrency()) * split.perThread : 1;
  std::size_t chunk = (n + wanted - 1) / wanted;
  chunk = std::min(std::max(chunk, g), std::max(split.maxChunk, g));
  chunk = (chunk + g - 1) / g * g;
  const std::size_t parts = (n + chunk - 1) / chunk;
  auto range = [&](unsigned p) { body(p * chunk, std::min(n, (p + 1) * chunk)); };
  if (ex && parts > 1) {
    ex->run(unsigned(parts), range);
  } else {
    for (std::size_t p = 0; p < parts; ++p) range(unsigned(p));
  }
}

/// The one parallel reduce: map(begin, end) -> T over the ranges of parallelFor, combined in
/// range order with combine(T& into, const T& part), so the result does not depend on which
/// thread ran what.
template <class T, class Map, class Combine>
T parallelReduce(Executor* ex, std::size_t n, Split split, T identity, Map map, Combine combine) {
  std::vector<std::pair<std::size_t, T>> parts;
  std::mutex m;
  parallelFor(ex, n, split, [&](std::size_t b, std::size_t e) {
    T part = map(b, e);
    std::lock_guard lock(m);
    parts.emplace_back(b, std::move(part));
  });
  std::sort(parts.begin(), parts.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& p : parts) combine(identity, p.second);
  return identity;
}

}  // namespace lp
