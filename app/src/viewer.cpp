#include "viewer.h"

#include <chrono>
#include <thread>

#include "progress.h"
#include "scene.h"
#include "scene_gl.h"

namespace lp::cli {

Viewer::Viewer(const ViewerSpec& spec, const Mesh& mesh) {
  ctx = openContext(spec.backend, spec.size, spec.headlessSize, spec.gpu);
  input = std::make_unique<WindowInput>(*ctx);
  const bool windowed = window();
  dynamicResolution = DynamicResolution(windowed && spec.keepRate && !spec.fullResolution &&
                                        gl::isSoftwareRenderer(ctx->describe()));
  renderer = std::make_unique<gl::Renderer>();
  loadModel(*renderer, mesh);
  gpuTimer = std::make_unique<gl::GpuTimer>();
  hasGpuTimer = !gl::isSoftwareRenderer(ctx->describe());
  const bool shown = windowed ? !spec.noHud : spec.hud;
  if (shown || windowed) {
    hud = std::make_unique<Hud>(*ctx);
    state.hud = shown;
  }
}

void Viewer::draw(double lastFrameMs) {
  const glm::ivec2 fb = ctx->framebufferSize();
  const HudLayout layout = hudLayout(fb);
  renderer->draw(fb, framedBesideHud(state.camera, layout, hud && state.hud),
                 dynamicResolution.apply(state.shading));
  if (!hud || !(state.hud || state.help)) return;
  hud->setNote(dynamicResolution.describe());
  hud->draw(layout, *renderer, state, lastFrameMs);
}

void Viewer::run(const ViewerLoop& loop) {
  RateTitle rate;
  double lastMs = 0;
  while (!ctx->shouldClose() && !stopRequested()) {
    const auto keys = handleInput(*input, hud.get(), state, loop.canPause);
    gpuTimer->beginFrame();
    const Turn turn = loop.before ? loop.before(keys) : Turn::Draw;
    if (turn == Turn::Stop) break;
    if (turn == Turn::Wait) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      continue;
    }
    StageClock clock;
    gpuTimer->begin(gl::GpuTimer::Render);
    draw(lastMs);
    gpuTimer->end();
    gl::Renderer::finish();
    lastMs = clock.lap(Stage::Render);
    dynamicResolution.update(lastMs);
    if (loop.drawn && !loop.drawn(lastMs)) break;
    ctx->present();
    if (!loop.title) continue;
    const auto [prefix, suffix] = loop.title();
    rate.tick(*input, prefix, suffix);
  }
}

std::optional<double> Viewer::gpuMs(gl::GpuTimer::Stage stage) const {
  if (!hasGpuTimer) return std::nullopt;
  const std::optional<double> ms = gpuTimer->ms(stage);
  return ms && *ms > 0 ? ms : std::nullopt;
}

}  // namespace lp::cli
