#pragma once
// The one viewer of view, replay and live: the GL context that came up (a window, or headless),
// the window's input, the renderer with its model, the HUD and dynamic resolution. A frame is
// drawn the same way for all of them (draw), and a window, or a camera headless, runs one loop
// (run) whose turns each command fills in: what a turn takes before it draws, what it does with a
// drawn frame, and the title.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dynamic_resolution.h"
#include "hud.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/gl/gpu_timer.h"
#include "liveprobe/gl/mesh.h"
#include "liveprobe/gl/renderer.h"
#include "settings.h"
#include "window_input.h"

namespace lp::cli {

struct ViewerSpec {
  gl::Backend backend = gl::Backend::Auto;
  Size size{1280, 720};
  Size headlessSize{0, 0};      ///< where Auto finds no display (0: `size`)
  bool hud = false;             ///< --hud: the HUD in headless output too
  bool noHud = false;           ///< --no-hud: a window starts with the HUD hidden
  bool fullResolution = false;  ///< --full-resolution: no dynamic resolution
  bool keepRate = true;         ///< a window on software GL keeps its rate (dynamic_resolution.h)
  int gpu = -1;                 ///< --gpu: the EGL device
};

/// What a turn of the loop does once the input is read.
enum class Turn : std::uint8_t {
  Draw,  ///< draw and present a frame
  Wait,  ///< nothing to draw yet: poll again shortly
  Stop,  ///< end the loop
};

struct ViewerLoop {
  bool canPause = false;  ///< Space and Right mean something (a stream)
  /// After the input, before drawing: the keys pressed; what the turn does.
  std::function<Turn(const std::vector<KeyAction>& keys)> before;
  /// After drawing, the frame's time to completion in ms, before it is presented; false: stop
  /// with this frame drawn and not presented (a screenshot reads it back).
  std::function<bool(double ms)> drawn;
  /// The window title's prefix and suffix around its frame rate (none: the title is left).
  std::function<std::pair<std::string, std::string>()> title;
};

class Viewer {
 public:
  /// Opens the context (lp::Error, or gl::ContextError from GL), the input, the renderer with
  /// `mesh`, and the HUD a window always has (H shows it) or that --hud asks of headless output.
  Viewer(const ViewerSpec& spec, const Mesh& mesh);

  bool window() const { return !ctx->isHeadless(); }
  /// The model framed beside the HUD where it is shown, at the dynamic resolution, then the HUD.
  void draw(double lastFrameMs);
  /// Until the window closes, Ctrl-C, or a turn says stop. With a GPU timer, each turn's upload
  /// (the caller's, between begin and end of gl::GpuTimer::Upload in `before`) and render are
  /// timed on the GPU.
  void run(const ViewerLoop& loop);
  /// The GPU's time of a stage, read a few frames late; none without a GPU timer, before the
  /// first reading, or where it read 0.
  std::optional<double> gpuMs(gl::GpuTimer::Stage stage) const;

  std::unique_ptr<gl::GlContext> ctx;
  std::unique_ptr<WindowInput> input;  ///< before the HUD, whose ImGui backend chains to it
  std::unique_ptr<gl::Renderer> renderer;
  std::unique_ptr<Hud> hud;
  ViewState state;
  DynamicResolution dynamicResolution;
  /// Timer queries of the upload and the render (run()). A software rasterizer has no GPU timer
  /// (llvmpipe answers 0 or a few nanoseconds): the queries run, and gpuMs() reads none.
  std::unique_ptr<gl::GpuTimer> gpuTimer;
  bool hasGpuTimer = false;
};

}  // namespace lp::cli
