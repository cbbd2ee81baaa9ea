// The GL context backends and the factory that picks one. The only file that includes GLFW or
// OSMesa (as Filament's PlatformFactory.cpp holds all platform #ifs).
// clang-format off: glad's header must come first, standing in for <GL/gl.h>.
#include "liveprobe/gl/gl.h"
// clang-format on

#include <GL/osmesa.h>
#include <GLFW/glfw3.h>

#include <cstdio>
#include <cstdlib>
#include <utility>
#include <vector>

#include "liveprobe/gl/context.h"

namespace lp::gl {

namespace {

std::string rendererString() {
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return std::string(r ? r : "?") + ", GL " + (v ? v : "?");
}

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

class OsMesaContext final : public GlContext {
 public:
  explicit OsMesaContext(const ContextSpec& spec)
      : width_(spec.width),
        height_(spec.height),
        buffer_(std::size_t(spec.width) * spec.height * 4) {
    const int attribs[] = {OSMESA_FORMAT,
                           OSMESA_RGBA,
                           OSMESA_DEPTH_BITS,
                           24,
                           OSMESA_STENCIL_BITS,
                           0,
                           OSMESA_PROFILE,
                           OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION,
                           3,
                           OSMESA_CONTEXT_MINOR_VERSION,
                           3,
                           0};
    ctx_ = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!ctx_) throw ContextError("OSMesa: cannot create a GL 3.3 core context");
    makeCurrent();
    if (!gladLoadGL(reinterpret_cast<GLADloadfunc>(OSMesaGetProcAddress))) {
      OSMesaDestroyContext(ctx_);
      throw ContextError("OSMesa: cannot load GL 3.3 core functions");
    }
  }
  ~OsMesaContext() override { OSMesaDestroyContext(ctx_); }
  void makeCurrent() override {
    if (!OSMesaMakeCurrent(ctx_, buffer_.data(), GL_UNSIGNED_BYTE, width_, height_))
      throw ContextError("OSMesa: cannot make the context current");
  }
  void present() override {}
  glm::ivec2 framebufferSize() const override { return {width_, height_}; }
  bool shouldClose() const override { return false; }
  InputDelta pollEvents() override { return {}; }
  bool isHeadless() const override { return true; }
  std::string describe() const override { return "OSMesa offscreen (" + rendererString() + ")"; }
  void* nativeWindow() const override { return nullptr; }
  void setTitle(const std::string&) override {}
  void requestClose() override {}

 private:
  OSMesaContext ctx_ = nullptr;
  int width_, height_;
  std::vector<unsigned char> buffer_;
};

}  // namespace

namespace {
void checkSize(int width, int height) {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
    throw ContextError("bad framebuffer size " + std::to_string(width) + "x" +
                       std::to_string(height));
}
}  // namespace

std::unique_ptr<GlContext> createGlContext(const ContextSpec& spec) {
  checkSize(spec.width, spec.height);
  if (spec.backend != Backend::Headless) {
    glfwSetErrorCallback([](int, const char* msg) { glfwLastError() = msg ? msg : "?"; });
    // Without a display glfwInit() fails: the natural point to fall back to headless.
    const bool haveDisplay = std::getenv("DISPLAY") || std::getenv("WAYLAND_DISPLAY");
    if (haveDisplay && glfwInit()) return std::make_unique<GlfwContext>(spec);
    if (haveDisplay && spec.backend == Backend::Auto)  // named, but unusable: say why
      std::fprintf(stderr, "liveprobe: warning: no window on the display (%s): drawing headless\n",
                   glfwLastError().empty() ? "glfwInit failed" : glfwLastError().c_str());
    if (spec.backend == Backend::Window)
      throw ContextError(
          "cannot open a window (no display: " +
          (glfwLastError().empty() ? std::string("DISPLAY is not set") : glfwLastError()) + ")");
    if (spec.headlessWidth > 0 && spec.headlessHeight > 0) {
      ContextSpec headless = spec;
      headless.width = spec.headlessWidth, headless.height = spec.headlessHeight;
      checkSize(headless.width, headless.height);
      return std::make_unique<OsMesaContext>(headless);
    }
  }
  return std::make_unique<OsMesaContext>(spec);
}

}  // namespace lp::gl
