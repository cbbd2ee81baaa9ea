#include "window_input.h"

#include <utility>

#include "liveprobe/backends.h"
#if LIVEPROBE_WITH_GLFW
#include <GLFW/glfw3.h>
#endif

namespace lp::cli {

#if LIVEPROBE_WITH_GLFW
WindowInput::WindowInput(gl::GlContext& ctx) : ctx_(ctx), window_(ctx.window()) {
  if (!window_) return;
  GLFWwindow* window = window_;
  glfwSetWindowUserPointer(window, this);
  // Installed before Dear ImGui's backend, which chains to them.
  glfwSetScrollCallback(window, [](GLFWwindow* w, double, double dy) {
    if (auto* self = static_cast<WindowInput*>(glfwGetWindowUserPointer(w)))
      self->input_.scroll += float(dy);
  });
  glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int mods) {
    if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
    if (key == GLFW_KEY_ESCAPE || key == GLFW_KEY_Q) {
      glfwSetWindowShouldClose(w, GLFW_TRUE);
      return;
    }
    auto* self = static_cast<WindowInput*>(glfwGetWindowUserPointer(w));
    if (!self) return;
    auto& keys = self->input_.keys;
    switch (key) {
      case GLFW_KEY_SPACE:
        if (action == GLFW_PRESS) keys.push_back(KeyAction::Pause);
        break;
      case GLFW_KEY_RIGHT:
        keys.push_back(KeyAction::Step);
        break;
      case GLFW_KEY_R:
        keys.push_back(KeyAction::ResetView);
        break;
      case GLFW_KEY_S:
        if (mods & GLFW_MOD_CONTROL) keys.push_back(KeyAction::Save);
        break;
      case GLFW_KEY_B:
        keys.push_back(KeyAction::ToggleBackground);
        break;
      case GLFW_KEY_H:
        keys.push_back(KeyAction::ToggleHud);
        break;
      case GLFW_KEY_F1:
        keys.push_back(KeyAction::Help);
        break;
      default:
        break;
    }
  });
  // The keys that are characters, whatever the keyboard layout: one press is one character
  // (shifted = and keypad + both type '+'; as keys as well they would count twice).
  glfwSetCharCallback(window, [](GLFWwindow* w, unsigned codepoint) {
    auto* self = static_cast<WindowInput*>(glfwGetWindowUserPointer(w));
    if (!self) return;
    auto& keys = self->input_.keys;
    if (codepoint == '?') keys.push_back(KeyAction::Help);
    if (codepoint == '+' || codepoint == '=') keys.push_back(KeyAction::ExposureUp);
    if (codepoint == '-') keys.push_back(KeyAction::ExposureDown);
  });
  glfwGetCursorPos(window, &lastX_, &lastY_);
}

WindowInput::~WindowInput() {
  if (!window_) return;
  GLFWwindow* window = window_;
  glfwSetScrollCallback(window, nullptr);
  glfwSetKeyCallback(window, nullptr);
  glfwSetCharCallback(window, nullptr);
  glfwSetWindowUserPointer(window, nullptr);
}

InputDelta WindowInput::poll() {
  ctx_.pollEvents();
  if (!window_) return {};
  GLFWwindow* window = window_;
  double x, y;
  glfwGetCursorPos(window, &x, &y);
  if (glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS)
    input_.drag = {float(x - lastX_), float(y - lastY_)};
  lastX_ = x, lastY_ = y;
  return std::exchange(input_, {});
}

void WindowInput::setTitle(const std::string& title) {
  if (window_) glfwSetWindowTitle(window_, title.c_str());
}
#else
WindowInput::WindowInput(gl::GlContext& ctx) : ctx_(ctx), window_(nullptr) {}
WindowInput::~WindowInput() = default;
InputDelta WindowInput::poll() {
  ctx_.pollEvents();
  return {};
}
void WindowInput::setTitle(const std::string&) {}
#endif

}  // namespace lp::cli
