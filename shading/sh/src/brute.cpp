#include "liveprobe/sh/brute.h"

#include <algorithm>
#include <atomic>
#include <thread>

namespace lp {

std::vector<Rgb> bruteIrradiance(const float* rgb, std::size_t pixelStride,
                                 const SphereSample* samples, std::size_t count,
                                 const std::vector<glm::vec3>& normals, Executor* executor,
                                 const BruteProgress& progress) {
  // Structure-of-arrays copy of the non-empty pixels with radiance pre-multiplied by dw, so the
  // inner loop is five contiguous streams the compiler vectorises (this file is compiled with
  // reassociation allowed; see shading/CMakeLists.txt).
  std::vector<float> wx, wy, wz, lr, lg, lb;
  for (auto* v : {&wx, &wy, &wz, &lr, &lg, &lb}) v->reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const SphereSample& s = samples[i];
    if (s.solidAngle == 0.0f) continue;
    const float* p = rgb + i * pixelStride;
    wx.push_back(s.dir.x);
    wy.push_back(s.dir.y);
    wz.push_back(s.dir.z);
    lr.push_back(p[0] * s.solidAngle);
    lg.push_back(p[1] * s.solidAngle);
    lb.push_back(p[2] * s.solidAngle);
  }
  const std::size_t n = wx.size();
  std::vector<Rgb> out(normals.size());
  const auto caller = std::this_thread::get_id();
  std::atomic<bool> stop{false};
  std::atomic<std::size_t> started{0};
  // Ranges of at most 16 normals, so progress reaches the caller often and a stop is quick.
  parallelFor(executor, normals.size(), Split{1, 4, 16}, [&](std::size_t t0, std::size_t t1) {
    for (std::size_t t = t0; t < t1; ++t) {
      if (stop.load(std::memory_order_relaxed)) return;
      const std::size_t done = started.fetch_add(1, std::memory_order_relaxed);
      if (progress && std::this_thread::get_id() == caller && !progress(done)) {
        stop = true;  // the other threads finish the normal they hold
        return;
      }
      const glm::vec3 nrm = normals[t];
      double er = 0, eg = 0, eb = 0;
      constexpr std::size_t kBlock = 4096;
      for (std::size_t b0 = 0; b0 < n; b0 += kBlock) {
        const std::size_t b1 = std::min(n, b0 + kBlock);
        float r = 0, g = 0, b = 0;
        for (std::size_t i = b0; i < b1; ++i) {
          const float c = std::max(0.0f, nrm.x * wx[i] + nrm.y * wy[i] + nrm.z * wz[i]);
          r += c * lr[i];
          g += c * lg[i];
          b += c * lb[i];
        }
        er += r;
        eg += g;
        eb += b;
      }
      out[t] = Rgb(float(er), float(eg), float(eb));
    }
  });
  return out;
}

}  // namespace lp
