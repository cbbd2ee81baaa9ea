#pragma once
// How much other programs held this process back: over its threads, the time each waited on a run
// queue for a CPU against the time it ran (Linux's scheduler statistics,
// /proc/self/task/*/schedstat: run ns, wait ns, timeslices). 1 + wait / run is the slowdown that
// sharing the CPUs alone explains: about 1.06 on an idle 2-core machine (a process's own threads
// wait for each other a little), 4.1 beside six stress-ng workers there. The calibration kernel,
// the fastest of many short repetitions, sees the machine's speed and not this; a stage's time
// sees both.
#include <map>
#include <string>

namespace lp::bench {

class Contention {
 public:
  Contention();
  /// 1 + waited / ran since construction, over the threads alive now (a thread that ended took
  /// its counts with it); 1 where the kernel keeps no statistics.
  double factor() const;

 private:
  struct Times {
    double run = 0, wait = 0;
  };
  static std::map<std::string, Times> read();
  std::map<std::string, Times> start_;
};

}  // namespace lp::bench
