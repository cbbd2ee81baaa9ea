// Subcommands that draw: render (one image) and view (an interactive window).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>

#include "commands.h"
#include "dynamic_resolution.h"
#include "environment.h"
#include "gpu_projection.h"
#include "hud.h"
#include "liveprobe/sh/error.h"
#include "progress.h"
#include "scene.h"
#include "scene_gl.h"
#include "viewer.h"

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
    "tone map, sRGB, 4x MSAA), with the environment behind it. Offscreen when there is no display\n"
    "(or with --headless): EGL on a GPU where there is one, else OSMesa on the CPU (--gl picks);\n"
    "otherwise in a GLFW window, read back before it is shown.",
    concat(concat(lightingOptions(), sceneOptions()),
           {opt::size("image size", 16384, "1280x720", "Output"),
            opt::out("FILE.png", "output image, .png or .jpg (default render.png)",
                     {".png", ".jpg", ".jpeg"}, "Output"),
            hudOptions("Output", false)[0]}),
    0,
    0};

namespace {

/// Whether the lighting is given at all: the error that names the three ways to give it, before
/// any context opens.
void lightingGiven(const Settings& s) {
  const LightingSettings& l = s.lighting;
  if (!l.env && !l.coeffs && l.coeff.empty())
    throw Error("give the lighting: --env FILE, --coeffs FILE.json or --coeff NAME=VALUE");
}

/// The lighting every drawing command needs, an --env map projected where --projection says in
/// the viewer's context (current).
Lighting requireLighting(const Settings& s, const gl::GlContext& ctx) {
  gl::GpuFrameProjection gpu;
  std::function<Sh9(const ProjectionJob&)> projectWith;
  if (s.lighting.env && projectsOnGpu(s.scene.projection, ctx))
    projectWith = [&gpu](const ProjectionJob& job) { return gpu(job); };
  return std::move(*lightingFrom(s, projectWith));
}

/// A HUD that shows a still's lighting (one sample, no stage times).
void showStill(Hud& hud, const LightingSettings& from, const Lighting& lighting) {
  const std::string source = from.env ? *from.env : from.coeffs ? *from.coeffs : "--coeff";
  hud.setSource(source, from.env ? std::string(layoutName(lighting.layout.layout)) : "coefficients",
                false, true);
  HudSample s;
  s.radiance = s.unsmoothed = lighting.radiance;
  s.lights = lighting.lights;
  hud.push(s);
}

}  // namespace

int runRender(const Args& a) {
  const Settings& s = a.settings();
  const auto size = s.output.size.value_or(Size{1280, 720});
  const std::string out = s.output.out.value_or("render.png");
  lightingGiven(s);
  const gl::Camera camera = cameraFrom(s.scene);
  const Mesh mesh = meshFrom(s.scene);
  // The viewer's own frame, as view and replay draw theirs: the model framed beside the HUD
  // where --hud shows it, at full resolution.
  std::string described;
  try {
    Viewer v(
        {glBackend(s.scene), size, size, s.output.hud, !s.output.hud, true, false, s.scene.gpu},
        mesh);
    const Lighting lighting = requireLighting(s, *v.ctx);
    v.state.camera = camera;
    v.state.shading =
        shadingFrom(s.scene, lighting.radiance, !lighting.background.empty(), lighting.lights);
    loadLighting(*v.renderer, lighting);
    if (v.hud && s.output.hud) showStill(*v.hud, s.lighting, lighting);
    v.draw(0.0);
    const glm::ivec2 fb = v.ctx->framebufferSize();
    const auto px = gl::Renderer::readRgb8(fb);
    saveRgb8(out, fb.x, fb.y, px.data());
    described = v.ctx->describe();
    if (s.lighting.env)
      described += lighting.projectedOn == ProjectedOn::Gpu ? "; --env projected on the GPU"
                                                            : "; --env projected on the CPU";
  } catch (const gl::ContextError& e) {
    throw Error(std::string("GL: ") + e.what());
  }
  errs() << "liveprobe: " << out << " (" << mesh.triangleCount() << " triangles, " << described
         << ")\n";
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
           concat({opt::size("window size", 16384, "1280x720", "Output"),
                   fileOption("--screenshot", "FILE.png",
                              "save the last frame here and exit (with --frames)",
                              {".png", ".jpg", ".jpeg"}, LP_FIELD(output.screenshot), "Output"),
                   opt::frames("number of frames to render before the screenshot", 1000000, "1",
                               "Output"),
                   textOption("--save-coeffs", "FILE.json",
                              "where the coefficient panel's Save writes (default "
                              "coeffs-edited.json)",
                              LP_FIELD(output.saveCoeffs), "Output")},
                  hudOptions("Output", true))),
    0,
    0,
    {},
    checkHudOptions};

namespace {

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
  const Settings& s = a.settings();
  lightingGiven(s);
  const gl::Camera camera = cameraFrom(s.scene);
  const Mesh mesh = meshFrom(s.scene);
  const bool screenshot = s.output.screenshot.has_value();
  const std::int64_t frames = s.output.frames.value_or(1);
  try {
    // A screenshot is drawn as asked; an interactive window keeps its rate.
    Viewer v({glBackend(s.scene),
              s.output.size.value_or(Size{1280, 720}),
              {},
              s.output.hud,
              s.output.noHud,
              s.scene.fullResolution,
              !screenshot,
              s.scene.gpu},
             mesh);
    if (!v.window() && !screenshot) {
      requireBackend(OptionalBackend::Window, "", "use --screenshot, or liveprobe render");
      throw Error("no display to open a window on (use --screenshot, or liveprobe render)");
    }
    Lighting lighting = requireLighting(s, *v.ctx);
    v.state.camera = v.state.initialCamera = camera;
    v.state.shading =
        shadingFrom(s.scene, lighting.radiance, !lighting.background.empty(), lighting.lights);
    loadLighting(*v.renderer, lighting);
    if (v.hud) {
      showStill(*v.hud, s.lighting, lighting);
      v.hud->enableEditor(&lighting.radiance, s.output.saveCoeffs);
    }
    std::vector<double> frameMs;
    ViewerLoop loop;
    loop.before = [&](const std::vector<KeyAction>& keys) {
      if (v.hud && std::count(keys.begin(), keys.end(), KeyAction::Save))
        std::fprintf(stderr, "liveprobe: %s\n", v.hud->saveCoefficients().c_str());
      return Turn::Draw;
    };
    loop.drawn = [&](double ms) {
      frameMs.push_back(ms);
      if (v.hud && v.hud->edited()) {  // the model lit by the edited coefficients from now on
        v.renderer->setLighting(lighting.radiance, lighting.lights);
        HudSample sample;
        sample.radiance = sample.unsmoothed = lighting.radiance;
        sample.lights = lighting.lights;
        v.hud->push(sample);
      }
      if (!screenshot || std::int64_t(frameMs.size()) < frames) return true;
      saveScreenshot(*s.output.screenshot, *v.ctx, frameMs, mesh.triangleCount());
      return false;
    };
    loop.title = [] { return std::pair<std::string, std::string>{"liveprobe view", ""}; };
    v.run(loop);
  } catch (const gl::ContextError& e) {
    throw Error(std::string("GL: ") + e.what());
  }
  return stopRequested() ? kExitInterrupted : 0;
}

}  // namespace lp::cli
