#include "liveprobe/bench/calibration.h"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <string>

#include "liveprobe/capture/open_source.h"
#include "liveprobe/sh/simd.h"

namespace lp::bench {

namespace {

constexpr int kWidth = 512, kHeight = 256;

/// The calling thread on the n-th of the CPUs it may run on (in turn), for its lifetime.
class OnCpu {
 public:
  explicit OnCpu(std::size_t n) {
    if (pthread_getaffinity_np(pthread_self(), sizeof was_, &was_) != 0) return;
    const int count = CPU_COUNT(&was_);
    if (count < 2) return;
    int k = int(n % std::size_t(count));
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
      if (CPU_ISSET(cpu, &was_) && k-- == 0) {
        cpu_set_t one;
        CPU_ZERO(&one);
        CPU_SET(cpu, &one);
        pinned_ = pthread_setaffinity_np(pthread_self(), sizeof one, &one) == 0;
        break;
      }
  }
  ~OnCpu() {
    if (pinned_) pthread_setaffinity_np(pthread_self(), sizeof was_, &was_);
  }
  OnCpu(const OnCpu&) = delete;
  OnCpu& operator=(const OnCpu&) = delete;

 private:
  cpu_set_t was_{};
  bool pinned_ = false;
};

/// The scalar SIMD path for its lifetime, the one in use before again after.
struct ScalarPath {
  std::string was = simd::current();
  ScalarPath() { simd::select("scalar"); }
  ~ScalarPath() { simd::select(was); }
};

}  // namespace

CalibrationKernel::CalibrationKernel() : proj_(Layout::Equirect, kWidth, kHeight) {
  renderSyntheticSky(kWidth, kHeight, 0.5, sky_);
}

void CalibrationKernel::time() {
  const ScalarPath path;
  const OnCpu on(count_++);
  const auto t0 = std::chrono::steady_clock::now();
  Sh9 s;
  for (int r = 0; r < 10; ++r)
    s += proj_.project(PanoramaView::rgbF32(sky_.data(), kWidth, kHeight));
  volatile float sink = s.c[0].x;
  (void)sink;
  best_ = std::min(
      best_,
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
}

}  // namespace lp::bench
