// The GLFW window: the one file of liveprobe::gl that includes GLFW.
// clang-format off: glad's header must come first, standing in for <GL/gl.h>.
#include "liveprobe/gl/gl.h"
// clang-format on

#include <GLFW/glfw3.h>

#include <cstdlib>
#include <utility>

#include "context_backends.h"

namespace lp::gl {

namespace {

std::string& glfwLastError() {
  static std::string e;
  return e;
}

class GlfwContext final : public GlContext {
 public:
  explicit GlfwContext(const ContextSpec& spec) {
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    window_ = glfwCreateWindow(spec.width, spec.height, spec.title.c_str(), nullptr, nullptr);
    if (!window_) {
      glfwTerminate();
      throw ContextError("cannot create a GLFW window: " + glfwLastError());
    }
    glfwMakeContextCurrent(window_);
    if (!gladLoadGL(reinterpret_cast<GLADloadfunc>(glfwGetProcAddress))) {
      glfwDestroyWindow(window_);
      glfwTerminate();
      throw ContextError("GLFW window: cannot load GL 3.3 core functions");
    }
    glfwSwapInterval(spec.vsync ? 1 : 0);
    glfwSetWindowUserPointer(window_, this);
    // Installed before Dear ImGui's backend, which chains to them.
    glfwSetScrollCallback(window_, [](GLFWwindow* w, double, double dy) {
      static_cast<GlfwContext*>(glfwGetWindowUserPointer(w))->input_.scroll += float(dy);
    });
    glfwSetKeyCallback(window_, [](GLFWwindow* w, int key, int, int action, int mods) {
      if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
      auto* self = static_cast<GlfwContext*>(glfwGetWindowUserPointer(w));
      if (key == GLFW_KEY_ESCAPE || key == GLFW_KEY_Q) {
        glfwSetWindowShouldClose(w, GLFW_TRUE);
        return;
      }
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
    glfwSetCharCallback(window_, [](GLFWwindow* w, unsigned codepoint) {
      auto& keys = static_cast<GlfwContext*>(glfwGetWindowUserPointer(w))->input_.keys;
      if (codepoint == '?') keys.push_back(KeyAction::Help);
      if (codepoint == '+' || codepoint == '=') keys.push_back(KeyAction::ExposureUp);
      if (codepoint == '-') keys.push_back(KeyAction::ExposureDown);
    });
    glfwGetCursorPos(window_, &lastX_, &lastY_);
  }
  ~GlfwContext() override {
    glfwDestroyWindow(window_);
    glfwTerminate();
  }
  void makeCurrent() override { glfwMakeContextCurrent(window_); }
  void present() override { glfwSwapBuffers(window_); }
  glm::ivec2 framebufferSize() const override {
    int w = 0, h = 0;
    glfwGetFramebufferSize(window_, &w, &h);
    return {w, h};
  }
  bool shouldClose() const override { return glfwWindowShouldClose(window_); }
  InputDelta pollEvents() override {
    glfwPollEvents();
    double x, y;
    glfwGetCursorPos(window_, &x, &y);
    if (glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS)
      input_.drag = {float(x - lastX_), float(y - lastY_)};
    lastX_ = x, lastY_ = y;
    return std::exchange(input_, {});
  }
  bool isHeadless() const override { return false; }
  std::string describe() const override { return "GLFW window (" + rendererString() + ")"; }
  void* nativeWindow() const override { return window_; }
  void setTitle(const std::string& title) override { glfwSetWindowTitle(window_, title.c_str()); }
  void requestClose() override { glfwSetWindowShouldClose(window_, GLFW_TRUE); }

 private:
  GLFWwindow* window_ = nullptr;
  InputDelta input_;
  double lastX_ = 0, lastY_ = 0;
};

}  // namespace

std::unique_ptr<GlContext> openWindow(const ContextSpec& spec, std::string& whyNot) {
  glfwSetErrorCallback([](int, const char* msg) { glfwLastError() = msg ? msg : "?"; });
  // Without a display glfwInit() fails: the natural point to fall back to headless.
  if (!std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY")) {
    whyNot = "DISPLAY is not set";
    return nullptr;
  }
  if (!glfwInit()) {
    whyNot = glfwLastError().empty() ? "glfwInit failed" : glfwLastError();
    return nullptr;
  }
  return std::make_unique<GlfwContext>(spec);
}

}  // namespace lp::gl
