#include "liveprobe/sh/executor.h"

#include <string>
#include <system_error>

#include "liveprobe/sh/error.h"

namespace lp {

ThreadPool::ThreadPool(unsigned threads) {
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  try {
    for (unsigned i = 1; i < threads; ++i) workers_.emplace_back([this] { work(); });
  } catch (const std::system_error& e) {
    stop();
    throw Error("cannot start " + std::to_string(threads) + " threads (" + e.what() + ")");
  }
}

ThreadPool::~ThreadPool() { stop(); }

void ThreadPool::stop() {
  {
    std::lock_guard lock(mutex_);
    quit_ = true;
  }
  start_.notify_all();
  for (auto& t : workers_) t.join();
  workers_.clear();
}

void ThreadPool::run(unsigned tasks, const std::function<void(unsigned)>& fn) {
  if (workers_.empty() || tasks <= 1) {
    for (unsigned i = 0; i < tasks; ++i) fn(i);
    return;
  }
  std::unique_lock lock(mutex_);
  fn_ = &fn;
  tasks_ = tasks;
  next_ = 0;
  finished_ = 0;
  ++generation_;
  lock.unlock();
  start_.notify_all();
  // The caller works too.
  for (;;) {
    lock.lock();
    if (next_ >= tasks_) break;
    const unsigned i = next_++;
    lock.unlock();
    fn(i);
    lock.lock();
    ++finished_;
    lock.unlock();
  }
  done_.wait(lock, [&] { return finished_ == tasks_; });
  fn_ = nullptr;
}

void ThreadPool::work() {
  std::uint64_t seen = 0;
  std::unique_lock lock(mutex_);
  for (;;) {
    start_.wait(lock, [&] { return quit_ || (generation_ != seen && next_ < tasks_); });
    if (quit_) return;
    seen = generation_;
    while (next_ < tasks_) {
      const unsigned i = next_++;
      const auto* fn = fn_;
      lock.unlock();
      (*fn)(i);
      lock.lock();
      if (++finished_ == tasks_) done_.notify_all();
    }
  }
}

}  // namespace lp
