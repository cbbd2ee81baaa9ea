#pragma once
// The calibration kernel: a fixed amount of the machine's own kind of work (projecting a fixed
// synthetic frame, single thread), timed in the same run as the stages. Stage times divided by it
// compare across machines, so a slower machine is not a regression.
//
// It is the machine's speed, not its load: the fastest of many repetitions of a few milliseconds
// each (shorter than a scheduler's time slice), since a repetition that other work interrupts
// only reads slower. Spread the repetitions over the whole run (one before each frame): each runs
// on the next of the CPUs the process may use, in turn, because on a 2-core virtual machine one
// core can be slower for seconds (its host busy): 21 repetitions in a row, on whichever core,
// read 3.2 to 4.9 ms from one run to the next while the stages did not move; spread, ten runs
// read 3.28 to 3.61 ms. (A median, not the fastest, read 2.5 ms in one run and 6.4 ms in the next
// on two busy cores.) It runs on the scalar path whatever the CPU offers: the stages it stands
// for (decode, GL on llvmpipe) gain little from AVX-512, so a kernel on the widest path would make
// a machine that has it look slower than it is (a render of 14 ms read as 22 against an AVX2
// baseline).
#include <cstddef>
#include <limits>
#include <vector>

#include "liveprobe/sh/projector.h"

namespace lp::bench {

class CalibrationKernel {
 public:
  CalibrationKernel();
  /// One repetition, timed, on the next CPU in turn and on the scalar path (the SIMD path in use
  /// before is in use again after).
  void time();
  /// The fastest repetition so far, ms (infinity before the first).
  double speed() const { return best_; }
  std::size_t repetitions() const { return count_; }

 private:
  std::vector<float> sky_;
  Projector proj_;
  std::size_t count_ = 0;
  double best_ = std::numeric_limits<double>::infinity();
};

}  // namespace lp::bench
