#pragma once
// The on-screen HUD of view, replay and live (Dear ImGui), and the interactive state its keys
// and sliders change. In a window it uses ImGui's GLFW backend for input; headless (--hud) the
// same HUD is drawn into the offscreen frame, so tests and recorded frames show it.
#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "liveprobe/capture/processed_frame.h"
#include "liveprobe/capture/stages.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/gl/renderer.h"
#include "liveprobe/hdr/merge.h"
#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/sh.h"
#include "window_input.h"

namespace lp::cli {

/// One drawn frame's numbers, for the HUD's history plots.
struct HudSample {
  std::uint64_t frame = 0;
  double time = 0;            ///< the source's timestamp, seconds
  StageTimes times;           ///< up to render (a window reads nothing back)
  double latencyMs = 0;       ///< capture to shown
  Sh9 radiance;               ///< as lit (after rotation and smoothing)
  Sh9 unsmoothed;             ///< before smoothing (equal to radiance without --smooth)
  std::vector<Light> lights;  ///< as lit (--sun): marked on the panorama inset
  FrameConfidence confidence;
  bool held = false;  ///< the lighting is the last good frame's (--hold-below)
  GpuTimes gpu;       ///< the GPU's own times, where there is a GPU timer
};

struct HudCounters {
  std::size_t captured = 0, drawn = 0, dropped = 0, skipped = 0;
  double saturatedPerFrame = 0;
  /// A line from each record sink (--serve: clients and drops; --publish: messages lost).
  std::vector<std::string> sinks;
};

/// What the viewer's keys and the HUD's widgets change.
struct ViewState {
  gl::Camera camera, initialCamera;
  gl::ShadingSettings shading;
  bool hud = true;
  bool help = false;
  bool paused = false;
  int steps = 0;  ///< single-frame steps asked for while paused
};

/// Where the HUD's panels go in a frame of `size` pixels, and the part of it left for the model.
/// The panels scale with the frame (from 0.75 to 2 times their size at 1280x720); where the part
/// between them would be narrower than a fifth of the frame, the light panel is left out, then
/// the status panel too: the HUD never covers the model.
struct HudLayout {
  glm::ivec2 size{1, 1};  ///< the frame's
  float scale = 1.0f;
  bool status = false, light = false;  ///< which panels are drawn
  float margin = 0, statusWidth = 0, lightWidth = 0;
  glm::vec4 modelFrame{0.0f, 0.0f, 1.0f, 1.0f};  ///< as gl::Camera::frame
};
HudLayout hudLayout(glm::ivec2 size);

/// `camera` framed in the part of the frame the HUD leaves, when the HUD is shown.
gl::Camera framedBesideHud(gl::Camera camera, const HudLayout& layout, bool hudShown);

/// A panel as the last draw() laid it out, in pixels from the top left, and the height its
/// content took.
struct HudPanel {
  std::string name;
  glm::vec2 min{0.0f}, max{0.0f};
  float contentHeight = 0;
};

/// The window title's frame rate, set once a second: "PREFIX - N frames/s" (and SUFFIX).
class RateTitle {
 public:
  /// Counts one presented frame; once a second writes the title (a headless context has none).
  void tick(WindowInput& input, const std::string& prefix, const std::string& suffix = "");

 private:
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
  std::size_t frames_ = 0;
};

class Hud;

/// Polls the window's input and applies it to `state`: keys, orbit (left drag) and zoom (wheel),
/// except what the HUD has (ImGui wants the mouse or the keyboard). A window's Esc/Q close it
/// from the key callback. Returns the key presses, for the caller's own (Save: the coefficient
/// editor's, Hud::saveCoefficients). `canPause`: Space and Right mean something (replay).
std::vector<KeyAction> handleInput(WindowInput& input, const Hud* hud, ViewState& state,
                                   bool canPause);

class Hud {
 public:
  /// Creates the ImGui context on `ctx` (current). A window gets ImGui's GLFW input backend.
  explicit Hud(gl::GlContext& ctx);
  ~Hud();
  Hud(const Hud&) = delete;
  Hud& operator=(const Hud&) = delete;

  /// A still (render, view) shows no stage times, counters or history.
  void setSource(std::string source, std::string layout, bool smoothing, bool still = false);
  void push(const HudSample& s);
  void setCounters(const HudCounters& c) { counters_ = c; }
  /// A line under the rate (dynamic resolution's state); empty for none.
  void setNote(std::string note) { note_ = std::move(note); }
  /// What the source waits for while it has no stream (FrameSource::waitingFor): said under the
  /// confidence, the lighting held meanwhile; empty when it has its stream.
  void setSourceWaiting(std::string waiting) { waiting_ = std::move(waiting); }
  /// Turns on the coefficient editor (view): sliders edit `*radiance`; Save writes `savePath`.
  void enableEditor(Sh9* radiance, std::string savePath);
  /// Writes the edited coefficients as `liveprobe coeffs` JSON (atomically); returns what it did.
  std::string saveCoefficients();
  /// True when the editor changed the coefficients in the last draw().
  bool edited() const { return edited_; }

  /// ImGui has the mouse / keyboard (the viewer then ignores them).
  bool wantsMouse() const;
  bool wantsKeyboard() const;

  /// The panels of the last draw().
  const std::vector<HudPanel>& panels() const { return panels_; }

  /// Draws the HUD (and the help overlay) over the bound framebuffer laid out as `layout`, after
  /// the scene (drawn with framedBesideHud of the same layout). Headless, the window's controls
  /// (exposure, background, help) are left out: the exposure is written instead.
  void draw(const HudLayout& layout, gl::Renderer& renderer, ViewState& state, double frameMs);

 private:
  void drawStatus(ViewState& state, double frameMs, const HudLayout& layout, float maxHeight);
  void drawStatusTimes(float maxHeight);
  void drawLight(gl::Renderer& renderer, const HudLayout& layout, float maxHeight);
  void drawProbes(gl::Renderer& renderer, float maxHeight);
  void drawLightMarks(const std::vector<Light>& lights);
  void drawCoefficientBars(float maxHeight);
  void drawLightPlots(float maxHeight);
  void drawEditor(const HudLayout& layout);
  void recordPanel(const char* name);
  void applyScale(float scale);
  void drawHelp(ViewState& state);

  bool window_ = false;
  std::string source_, layout_, note_, waiting_;
  bool smoothing_ = false, still_ = false;
  std::deque<HudSample> history_;
  HudCounters counters_;
  Sh9* editing_ = nullptr;
  std::string savePath_, saveMessage_;
  bool edited_ = false;
  double fpsSmoothed_ = 0;
  bool laidOut_ = false;
  float scale_ = 0;  ///< the scale the style was last set to
  std::vector<HudPanel> panels_;
};

}  // namespace lp::cli
