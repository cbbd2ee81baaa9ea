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
#include <vector>

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

/// Input gathered since the last pollEvents().
struct InputDelta {
  glm::vec2 drag{0.0f};         ///< cursor movement with the left button held, in pixels
  float scroll = 0.0f;          ///< wheel steps
  std::vector<KeyAction> keys;  ///< in the order pressed
};

class GlContext {
 public:
  virtual ~GlContext() = default;
  virtual void makeCurrent() = 0;
  /// Shows the frame (window) or does nothing (headless).
  virtual void present() = 0;
  virtual glm::ivec2 framebufferSize() const = 0;
  virtual bool shouldClose() const = 0;
  virtual InputDelta pollEvents() = 0;
  virtual bool isHeadless() const = 0;
  /// "GLFW window" or "OSMesa offscreen", plus GL_RENDERER.
  virtual std::string describe() const = 0;
  /// The GLFWwindow* of a window (for Dear ImGui's GLFW backend); nullptr headless.
  virtual void* nativeWindow() const = 0;
  virtual void setTitle(const std::string& title) = 0;
  /// Asks the window to close (as Esc does).
  virtual void requestClose() = 0;
};

/// Creates a context and loads GL into it. Throws ContextError with the cause.
std::unique_ptr<GlContext> createGlContext(const ContextSpec& spec);

}  // namespace lp::gl
