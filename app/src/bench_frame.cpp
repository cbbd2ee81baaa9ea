#include "bench_frame.h"

#include <chrono>
#include <cstdio>

#include "liveprobe/sh/error.h"
#include "scene.h"
#include "scene_gl.h"

namespace lp::cli {

namespace {

// Busy-waits, so an injected delay costs CPU time like real work does.
void spin(double ms) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double, std::milli>(ms);
  while (std::chrono::steady_clock::now() < end) {
  }
}

/// Times a frame's GL work of one stage on the GPU.
template <class F>
void onGpuTimer(BenchScene& scene, gl::GpuTimer::Stage stage, F work) {
  scene.timer->begin(stage);
  work();
  scene.timer->end();
}

}  // namespace

BenchTimes timeFrame(BenchScene& scene, RunState& run, FrameSource& source,
                     const std::string& sourceName, Executor& pool, bool first) {
  StageClock clock;
  const auto injected = [&](Stage stage) {  // the injected busy work, in its stage
    for (int k = 0; k < kBenchStageCount; ++k)
      if (kBenchStages[std::size_t(k)] == stage) spin(scene.inject[std::size_t(k)]);
  };
  const auto lap = [&](Stage stage) {
    injected(stage);
    clock.lap(stage);
  };
  Frame& frame = *run.frame;
  if (!source.next(frame) && (!source.rewind() || !source.next(frame)))
    throw Error(sourceName + ": no frames to benchmark");
  lap(Stage::Grab);
  scene.timer->beginFrame();
  for (int k = 0; k < gl::GpuTimer::kStages; ++k)
    if (auto ms = scene.timer->justRead(gl::GpuTimer::Stage(k)))
      scene.gpuTimes[std::size_t(k)].push_back(*ms);
  FrameResult r;
  try {
    FrameRequest request{.background = true, .linearInto = run.linear};
    if (scene.gpuProjection)
      request.projectWith = [&](const ProjectionJob& job) {
        Sh9 whole;  // the upload, the passes and the read-back, on the GPU's timer
        onGpuTimer(scene, gl::GpuTimer::Project, [&] { whole = run.gpu(job); });
        return whole;
      };
    r = run.processor.run(run.frame, request, &pool);
    clock.skip();  // (timed by run() itself)
    clock.times += r.times;
  } catch (const Error& e) {
    throw Error(sourceName + ": " + e.what());
  }
  for (const Stage stage : {Stage::Convert, Stage::Project, Stage::Resample}) lap(stage);
  const Sh9& sh = r.lighting.radiance;
  run.last = sh;
  if (first) run.exposure = autoExposure(sh);
  gl::Renderer& renderer = *scene.viewer.renderer;
  renderer.setLighting(sh);
  onGpuTimer(scene, gl::GpuTimer::Upload, [&] { setBackground(renderer, r.background); });
  gl::Renderer::finish();
  lap(Stage::Upload);
  scene.viewer.state.shading.exposure = run.exposure;
  onGpuTimer(scene, gl::GpuTimer::Render, [&] { scene.viewer.draw(0.0); });
  gl::Renderer::finish();
  lap(Stage::Render);
  auto px = gl::Renderer::readRgb8(scene.viewer.ctx->framebufferSize());
  lap(Stage::Readback);
  BenchTimes t{};
  for (int k = 0; k < kBenchStageCount; ++k)
    t[std::size_t(k)] = clock.times[kBenchStages[std::size_t(k)]];
  return t;
}

nlohmann::ordered_json gpuSummary(const BenchScene& scene) {
  nlohmann::ordered_json g;
  if (!scene.timer->hasTimer()) {
    std::printf("GPU time: no GPU timer (%s)\n", scene.viewer.ctx->describe().c_str());
    g["timer"] = false;
    return g;
  }
  g["timer"] = true;
  std::string line;
  for (int k = 0; k < gl::GpuTimer::kStages; ++k) {
    const auto& v = scene.gpuTimes[std::size_t(k)];
    if (v.empty()) continue;
    const double med = percentile(v, 0.5);
    g[gl::GpuTimer::kNames[k]] = {{"median_ms", med}, {"frames", v.size()}};
    char b[96];
    std::snprintf(b, sizeof b, "%s%s %.3f ms", line.empty() ? "" : ", ", gl::GpuTimer::kNames[k],
                  med);
    line += b;
  }
  std::printf("GPU time (medians, timer queries): %s\n", line.empty() ? "none read" : line.c_str());
  return g;
}

}  // namespace lp::cli
