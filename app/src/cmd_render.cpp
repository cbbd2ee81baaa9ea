// Subcommands that draw: render (one image) and view (an interactive window).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>

#include "capture/error.h"
#include "commands.h"
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
    "[--env FILE [--layout ...] | --coeffs FILE.json | --coeff NAME=VALUE ...] [--model FILE|sphere]\n"
    "       [--size WxH] [--out OUT.png] [--headless] [--yaw D] [--pitch D] [--distance D] ...",
    "Renders one image of a model lit by nine SH coefficients (diffuse albedo * E / pi, exposure,\n"
    "tone map, sRGB), with the environment behind it. Offscreen through OSMesa when there is no\n"
    "display (or with --headless); otherwise in a GLFW window, read back before it is shown.",
    concat(concat(lightingOptions(), sceneOptions()),
           {{"--size", "WxH", "image size (default 1280x720)"},
            {"--out", "FILE.png", "output image (default render.png)"}}),
    0, 0};

int runRender(const Args& a) {
  const auto size = parseSize(a.get("--size", "1280x720"), "--size");
  const auto lighting = lightingFromArgs(a);
  if (!lighting) throw Error("render: give the lighting: --env FILE, --coeffs FILE.json or --coeff NAME=VALUE");
  const gl::Camera camera = cameraFromArgs(a);
  const gl::ShadingSettings shading = shadingFromArgs(a, lighting->radiance);
  const Mesh mesh = meshFromArgs(a);
  const std::string out = a.get("--out", "render.png");
  auto ctx = openContext(backendFromArgs(a), size);
  try {
    gl::Renderer renderer;
    loadScene(renderer, mesh, *lighting);
    const glm::ivec2 fb = ctx->framebufferSize();
    renderer.draw(fb, camera, shading);
    const auto px = gl::Renderer::readRgb8(fb);
    saveRgb8(out, fb.x, fb.y, px.data());
  } catch (const gl::ContextError& e) {
    throw Error(std::string("GL: ") + e.what());
  }
  std::cerr << "liveprobe render: " << out << " (" << mesh.triangleCount() << " triangles, "
            << ctx->describe() << ")\n";
  return 0;
}

const CommandSpec kViewSpec{
    "view",
    "[--env FILE [--layout ...] | --coeffs FILE.json | --coeff ...] [--model FILE|sphere]\n"
    "       [--size WxH] [--screenshot OUT.png --frames N] ...",
    "Opens an interactive window: drag with the left button to orbit, scroll to zoom, Esc or Q\n"
    "to quit. --screenshot OUT.png --frames N renders N frames, saves the last and exits.",
    concat(concat(lightingOptions(), sceneOptions()),
           {{"--size", "WxH", "window size (default 1280x720)"},
            {"--screenshot", "FILE.png", "save the last frame here and exit (with --frames)"},
            {"--frames", "N", "number of frames to render before the screenshot (default 1)"}}),
    0, 0};

int runView(const Args& a) {
  const auto size = parseSize(a.get("--size", "1280x720"), "--size");
  const auto lighting = lightingFromArgs(a);
  if (!lighting) throw Error("view: give the lighting: --env FILE, --coeffs FILE.json or --coeff NAME=VALUE");
  gl::Camera camera = cameraFromArgs(a);
  const gl::ShadingSettings shading = shadingFromArgs(a, lighting->radiance);
  const Mesh mesh = meshFromArgs(a);
  const bool screenshot = a.has("--screenshot");
  const int frames = a.integer("--frames", 1);
  if (frames < 1) throw Error("--frames " + a.get("--frames") + ": must be at least 1");
  auto ctx = openContext(backendFromArgs(a), size);
  if (ctx->isHeadless() && !screenshot)
    throw Error("view: no display to open a window on (use --screenshot, or liveprobe render)");
  try {
    gl::Renderer renderer;
    loadScene(renderer, mesh, *lighting);
    auto t0 = std::chrono::steady_clock::now();
    std::vector<double> frameMs;
    for (int frame = 0; !ctx->shouldClose(); ++frame) {
      const auto start = std::chrono::steady_clock::now();
      applyInput(camera, ctx->pollEvents());
      const glm::ivec2 fb = ctx->framebufferSize();
      renderer.draw(fb, camera, shading);
      gl::Renderer::finish();
      frameMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      if (screenshot && frame + 1 >= frames) {
        const auto px = gl::Renderer::readRgb8(fb);
        saveRgb8(a.get("--screenshot"), fb.x, fb.y, px.data());
        std::sort(frameMs.begin(), frameMs.end());
        std::fprintf(stderr, "liveprobe view: %s after %d frames, median frame %.2f ms (%dx%d, %zu triangles, %s)\n",
                     a.get("--screenshot").c_str(), frames, frameMs[frameMs.size() / 2], fb.x, fb.y,
                     mesh.triangleCount(), ctx->describe().c_str());
        break;
      }
      ctx->present();
      if ((frame + 1) % 120 == 0) {
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::fprintf(stderr, "liveprobe view: %.1f frames/s\n", 120.0 / s);
        t0 = std::chrono::steady_clock::now();
      }
    }
  } catch (const gl::ContextError& e) {
    throw Error(std::string("GL: ") + e.what());
  }
  return 0;
}

}  // namespace lp::cli
