#pragma once
// One GL context interface, two backends in the same binary: a GLFW window (X11; where the build
// has LIVEPROBE_WITH_GLFW) and OSMesa offscreen (Mesa llvmpipe). Each lives in its own file of
// src/, picked by context_factory.cpp; the renderer never sees GLFW or OSMesa. createGlContext()
// loads GL 3.3 core through glad for either.
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <stdexcept>
#include <string>

namespace lp::gl {

struct ContextError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class Backend : std::uint8_t { Auto, Window, Headless };

struct ContextSpec {
  Backend backend = Backend::Auto;  ///< Auto: a window when a display opens, else headless
  int width = 1280;
  int height = 720;
  std::string title = "liveprobe";
  bool vsync = true;
  /// The framebuffer's size when Auto comes up headless (0: width x height).
  int headlessWidth = 0, headlessHeight = 0;
};

/// What a platform provides for liveprobe to draw into (as Filament's OpenGLPlatform): a current
/// context, a framebuffer and, for a window, its events. Input and the title are the app's
/// (GLFW's callbacks on nativeWindow()).
class GlContext {
 public:
  virtual ~GlContext() = default;
  virtual void makeCurrent() = 0;
  /// Shows the frame (window) or does nothing (headless).
  virtual void present() = 0;
  virtual glm::ivec2 framebufferSize() const = 0;
  virtual bool shouldClose() const = 0;
  /// Processes the window's pending events (a headless context has none).
  virtual void pollEvents() = 0;
  virtual bool isHeadless() const = 0;
  /// "GLFW window" or "OSMesa offscreen", plus GL_RENDERER.
  virtual std::string describe() const = 0;
  /// The GLFWwindow* of a window (for the app's input and Dear ImGui's GLFW backend); nullptr
  /// headless.
  virtual void* nativeWindow() const = 0;
  /// Asks the window to close (as Esc does).
  virtual void requestClose() = 0;
};

/// Creates a context and loads GL into it. Throws ContextError with the cause.
std::unique_ptr<GlContext> createGlContext(const ContextSpec& spec);

}  // namespace lp::gl
