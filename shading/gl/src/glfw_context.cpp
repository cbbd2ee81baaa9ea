// The GLFW window: the one file of liveprobe::gl that includes GLFW.
// clang-format off: glad's header must come first, standing in for <GL/gl.h>.
#include "liveprobe/gl/gl.h"
// clang-format on

#include <GLFW/glfw3.h>

#include "liveprobe/backends.h"
#if LIVEPROBE_WITH_EGL
#define GLFW_EXPOSE_NATIVE_EGL
#include <GLFW/glfw3native.h>
#endif

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
    // An EGL context where the build has EGL, so that the capture thread's EGL context can share
    // its objects (ContextSpec::shareWith: the merged frame drawn where it was merged); else, or
    // where the display offers no EGL, the platform's own (GLX).
    if (LIVEPROBE_WITH_EGL) {
      glfwWindowHint(GLFW_CONTEXT_CREATION_API, GLFW_EGL_CONTEXT_API);
      window_ = glfwCreateWindow(spec.width, spec.height, spec.title.c_str(), nullptr, nullptr);
      egl_ = window_ != nullptr;
      glfwWindowHint(GLFW_CONTEXT_CREATION_API, GLFW_NATIVE_CONTEXT_API);
    }
    if (!window_)
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
    description_ =
        std::string("GLFW window, ") + (egl_ ? "EGL" : "GLX") + " (" + rendererString() + ")";
    backend_ = Backend::Window;
  }
  bool egl_ = false;  ///< the window's context is EGL's
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

WindowEgl windowEgl(const GlContext& window) {
#if LIVEPROBE_WITH_EGL
  const auto* w = dynamic_cast<const GlfwContext*>(&window);
  if (w && w->egl_) return {glfwGetEGLDisplay(), glfwGetEGLContext(w->window())};
#endif
  (void)window;
  return {};
}

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
