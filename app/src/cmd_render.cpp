// Subcommands that draw: render (one image) and view (an interactive window).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>

#include "commands.h"
#include "dynamic_resolution.h"
#include "hud.h"
#include "liveprobe/sh/error.h"
#include "progress.h"
#include "scene.h"

namespace lp::cli {

namespace {

std::vector<OptionSpec> concat(std::vector<OptionSpec> a, const std::vector<OptionSpec>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace

const CommandSpec kRenderSpec{
    "render",
    "",
    "Renders one image of a model lit by nine SH coefficients (diffuse albedo * E / pi, exposure,\n"
    "tone map, sRGB, 4x MSAA), with the environment behind it. Offscreen through OSMesa when "
    "there\n"
    "is no display (or with --headless); otherwise in a GLFW window, read back before it is shown.",
    concat(concat(lightingOptions(), sceneOptions()),
           {{"--size", "WxH", "image size, each side up to 16384 (default 1280x720)", false, false,
             "Output"},
            {"--out", "FILE.png", "output image, .png or .jpg (default render.png)", false, false,
             "Output"},
            hudOptions("Output", false)[0]}),
    0,
    0};

namespace {

/// The lighting every drawing command needs, or an error that names the three ways to give it.
Lighting requireLighting(const Args& a) {
  auto l = lightingFromArgs(a);
  if (!l) throw Error("give the lighting: --env FILE, --coeffs FILE.json or --coeff NAME=VALUE");
  return std::move(*l);
}

/// A HUD that shows a still's lighting (one sample, no stage times).
void showStill(Hud& hud, const Args& a, const Lighting& lighting) {
  const std::string source = a.has("--env")      ? a.get("--env")
                             : a.has("--coeffs") ? a.get("--coeffs")
                                                 : "--coeff";
  hud.setSource(source,
                a.has("--env") ? std::string(layoutName(lighting.layout.layout)) : "coefficients",
                false, true);
  HudSample s;
  s.radiance = s.unsmoothed = lighting.radiance;
  s.lights = lighting.lights;
  hud.push(s);
}

}  // namespace

int runRender(const Args& a) {
  const auto size = parseSize(a.get("--size", "1280x720"), "--size");
  const std::string out = a.get("--out", "render.png");
  requireExtension(out, "--out", {".png", ".jpg", ".jpeg"});
  const Lighting lighting = requireLighting(a);
  const gl::Camera camera = cameraFromArgs(a);
  ViewState state;
  state.camera = camera;
  state.shading =
      shadingFromArgs(a, lighting.radiance, lighting.background.has_value(), lighting.lights);
  const Mesh mesh = meshFromArgs(a);
  auto ctx = openContext(backendFromArgs(a), size);
  try {
    gl::Renderer renderer;
    loadScene(renderer, mesh, lighting);
    const glm::ivec2 fb = ctx->framebufferSize();
    const HudLayout layout = hudLayout(fb);
    renderer.draw(fb, framedBesideHud(camera, layout, a.has("--hud")), state.shading);
    if (a.has("--hud")) {
      Hud hud(*ctx);
      showStill(hud, a, lighting);
      hud.draw(layout, renderer, state, 0.0);
    }
    const auto px = gl::Renderer::readRgb8(fb);
    saveRgb8(out, fb.x, fb.y, px.data());
  } catch (const gl::ContextError& e) {
    throw Error(std::string("GL: ") + e.what());
  }
  errs() << "liveprobe: " << out << " (" << mesh.triangleCount() << " triangles, "
         << ctx->describe() << ")\n";
  return 0;
}

const CommandSpec kViewSpec{
    "view",
    "",
    "Opens an interactive window with the HUD: drag with the left button to orbit, scroll to\n"
    "zoom; R resets the view, B toggles the background, H the HUD, +/- change the exposure, F1 or\n"
    "? shows the keys, Esc or Q quits. The coefficient panel edits the nine coefficients and "
    "saves\n"
    "them as JSON for render --coeffs. --screenshot OUT.png --frames N renders N frames, saves "
    "the\n"
    "last and exits (headless too).",
    concat(concat(lightingOptions(), sceneOptions()),
           {{"--size", "WxH", "window size (default 1280x720)", false, false, "Output"},
            {"--screenshot", "FILE.png", "save the last frame here and exit (with --frames)", false,
             false, "Output"},
            {"--frames", "N", "number of frames to render before the screenshot (default 1)", false,
             false, "Output"},
            {"--save-coeffs", "FILE.json",
             "where the coefficient panel's Save writes (default coeffs-edited.json)", false, false,
             "Output"},
            hudOptions("Output", true)[0],
            hudOptions("Output", true)[1]}),
    0,
    0};

namespace {

/// `view`'s window (or headless screenshot) and what it draws.
struct StillViewer {
  std::unique_ptr<gl::GlContext> ctx;
  std::unique_ptr<WindowInput> input;      ///< before the HUD, whose ImGui backend chains to it
  std::unique_ptr<gl::Renderer> renderer;  ///< made once ctx is current
  std::unique_ptr<Hud> hud;
  ViewState state;
  DynamicResolution dynamicResolution;

  /// One frame: input, the model, the HUD (and, when its editor changed the coefficients, the
  /// model lit by them from the next frame).
  void frame(Lighting& lighting, double lastMs) {
    const auto keys = handleInput(*input, hud.get(), state, false);
    if (hud && std::count(keys.begin(), keys.end(), KeyAction::Save))
      std::fprintf(stderr, "liveprobe: %s\n", hud->saveCoefficients().c_str());
    const glm::ivec2 fb = ctx->framebufferSize();
    const HudLayout layout = hudLayout(fb);
    renderer->draw(fb, framedBesideHud(state.camera, layout, hud && state.hud),
                   dynamicResolution.apply(state.shading));
    if (!hud || !(state.hud || state.help)) return;
    hud->setNote(dynamicResolution.describe());
    hud->draw(layout, *renderer, state, lastMs);
    if (!hud->edited()) return;
    renderer->setLighting(lighting.radiance, lighting.lights);
    HudSample s;
    s.radiance = s.unsmoothed = lighting.radiance;
    s.lights = lighting.lights;
    hud->push(s);
  }
};

/// The last frame saved, and what it was: frames, median frame time, size, model, GL.
void saveScreenshot(const std::string& path, const gl::GlContext& ctx, std::vector<double> frameMs,
                    std::size_t triangles) {
  const glm::ivec2 fb = ctx.framebufferSize();
  const auto px = gl::Renderer::readRgb8(fb);
  saveRgb8(path, fb.x, fb.y, px.data());
  const std::size_t frames = frameMs.size();
  std::sort(frameMs.begin(), frameMs.end());
  std::fprintf(stderr,
               "liveprobe: %s after %zu frame%s, median frame %.2f ms (%dx%d, %zu triangles, %s)\n",
               path.c_str(), frames, frames == 1 ? "" : "s", frameMs[frames / 2], fb.x, fb.y,
               triangles, ctx.describe().c_str());
}

}  // namespace

int runView(const Args& a) {
  installStopHandlers();
  const auto size = parseSize(a.get("--size", "1280x720"), "--size");
  Lighting lighting = requireLighting(a);
  StillViewer v;
  v.state.camera = v.state.initialCamera = cameraFromArgs(a);
  v.state.shading =
      shadingFromArgs(a, lighting.radiance, lighting.background.has_value(), lighting.lights);
  const Mesh mesh = meshFromArgs(a);
  checkHudOptions(a);
  const bool screenshot = a.has("--screenshot");
  if (screenshot)
    requireExtension(a.get("--screenshot"), "--screenshot", {".png", ".jpg", ".jpeg"});
  const int frames = a.integerIn("--frames", 1, 1, 1000000);
  v.ctx = openContext(backendFromArgs(a), size);
  v.input = std::make_unique<WindowInput>(*v.ctx);
  const bool window = !v.ctx->isHeadless();
  if (!window && !screenshot) {
    requireBackend(OptionalBackend::Window, "", "use --screenshot, or liveprobe render");
    throw Error("no display to open a window on (use --screenshot, or liveprobe render)");
  }
  try {
    v.renderer = std::make_unique<gl::Renderer>();
    loadScene(*v.renderer, mesh, lighting);
    if (window || a.has("--hud")) {
      v.hud = std::make_unique<Hud>(*v.ctx);
      showStill(*v.hud, a, lighting);
      v.hud->enableEditor(&lighting.radiance, a.get("--save-coeffs", "coeffs-edited.json"));
      v.state.hud = !window || !a.has("--no-hud");
    }
    // A screenshot is drawn as asked; an interactive window keeps its rate (dynamic_resolution.h).
    v.dynamicResolution = DynamicResolution(
        window && !screenshot && isSoftwareGl(v.ctx->describe()) && !a.has("--full-resolution"));
    RateTitle rate;
    std::vector<double> frameMs;
    while (!v.ctx->shouldClose() && !stopRequested()) {
      const auto start = std::chrono::steady_clock::now();
      v.frame(lighting, frameMs.empty() ? 0.0 : frameMs.back());
      gl::Renderer::finish();
      frameMs.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count());
      v.dynamicResolution.update(frameMs.back());
      if (screenshot && int(frameMs.size()) >= frames) {
        saveScreenshot(a.get("--screenshot"), *v.ctx, frameMs, mesh.triangleCount());
        break;
      }
      v.ctx->present();
      rate.tick(*v.input, "liveprobe view");
    }
  } catch (const gl::ContextError& e) {
    throw Error(std::string("GL: ") + e.what());
  }
  return stopRequested() ? kExitInterrupted : 0;
}

}  // namespace lp::cli
