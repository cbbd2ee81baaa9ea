#pragma once
// A window's input and title, from GLFW's callbacks on the context's window: the keys the viewer
// knows, a left-button drag and the wheel. Made before the HUD, whose Dear ImGui GLFW backend
// chains to these callbacks. A headless context (or a build without GLFW) has no input.
#include <cstdint>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "liveprobe/gl/context.h"

namespace lp::cli {

/// What a key press asks for. Keys arrive through GLFW's callbacks, so a tap shorter than a frame
/// is never lost; Esc and Q close the window from the callback itself.
enum class KeyAction : std::uint8_t {
  Pause,             ///< Space
  Step,              ///< Right arrow
  ResetView,         ///< R
  ToggleBackground,  ///< B
  ToggleHud,         ///< H
  ExposureUp,        ///< + or = (keypad +)
  ExposureDown,      ///< - (keypad -)
  Help,              ///< F1 or ?
  Save,              ///< Ctrl+S
};

/// Input gathered since the last poll().
struct InputDelta {
  glm::vec2 drag{0.0f};         ///< cursor movement with the left button held, in pixels
  float scroll = 0.0f;          ///< wheel steps
  std::vector<KeyAction> keys;  ///< in the order pressed
};

class WindowInput {
 public:
  /// Takes the window's callbacks (the context's window, if it has one).
  explicit WindowInput(gl::GlContext& ctx);
  ~WindowInput();
  WindowInput(const WindowInput&) = delete;
  WindowInput& operator=(const WindowInput&) = delete;

  /// Processes the window's events and returns the input since the last call.
  InputDelta poll();
  void setTitle(const std::string& title);

 private:
  gl::GlContext& ctx_;
  GLFWwindow* window_;  ///< nullptr headless
  InputDelta input_;
  double lastX_ = 0, lastY_ = 0;
};

}  // namespace lp::cli
