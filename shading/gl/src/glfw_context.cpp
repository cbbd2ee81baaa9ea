// The GLFW window: the one file of liveprobe::gl that includes GLFW.
// clang-format off: glad's header must come first, standing in for <GL/gl.h>.
#include "liveprobe/gl/gl.h"
// clang-format on

#include <GLFW/glfw3.h>

#include <cstdlib>

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
    description_ = "GLFW window (" + rendererString() + ")";
    backend_ = Backend::Window;
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
  void pollEvents() override { glfwPollEvents(); }
};

}  // namespace

void releaseWindowContext() {
  // (Before glfwInit, or after glfwTerminate, GLFW has no context to let go.)
  if (glfwGetCurrentContext()) glfwMakeContextCurrent(nullptr);
}

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
