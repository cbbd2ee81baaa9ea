#pragma once
// A small persistent pool for splitting one frame's projection across cores: run(n, fn) calls
// fn(0..n-1) on the workers and the caller, and returns when all are done. Threads are created
// once, so a 30 us projection does not pay tens of microseconds of thread start-up per frame.
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace lp {

class ThreadPool {
 public:
  /// `threads` in total, the caller included (1 = no workers).
  explicit ThreadPool(unsigned threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  unsigned size() const { return unsigned(workers_.size()) + 1; }
  void run(unsigned tasks, const std::function<void(unsigned)>& fn);

 private:
  void work();
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_, done_;
  const std::function<void(unsigned)>* fn_ = nullptr;
  unsigned tasks_ = 0, next_ = 0, finished_ = 0;
  std::uint64_t generation_ = 0;
  bool quit_ = false;
};

}  // namespace lp
