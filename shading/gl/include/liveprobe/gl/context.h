#pragma once
// One GL context interface, three backends in the same binary: a GLFW window (X11; where the
// build has LIVEPROBE_WITH_GLFW), EGL headless on a GPU (where it has LIVEPROBE_WITH_EGL) and
// OSMesa offscreen (Mesa llvmpipe, where it has LIVEPROBE_WITH_OSMESA). Each lives in its own
// file of src/, picked by context_factory.cpp; the renderer never sees GLFW, EGL or OSMesa.
// createGlContext() loads GL (3.3 core at least; 4.3 for the compute passes) through glad.
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "liveprobe/sh/error.h"

struct GLFWwindow;  // GLFW's window type; only the window backend and the app's input include GLFW

namespace lp::gl {

/// A GL failure (no context, a driver's error, a shader that does not compile): liveprobe's one
/// error type, so that wherever it happens the command says it in one line and exits 1.
struct ContextError : Error {
  using Error::Error;
};

/// Which context createGlContext() opens.
///   Auto:     a window when a display opens, else as Headless;
///   Headless: EGL on a GPU where EGL finds one, else OSMesa (the CPU rasterizer);
///   Window, Egl, OsMesa: that one or a ContextError (Egl takes a software device too).
enum class Backend : std::uint8_t { Auto, Window, Headless, Egl, OsMesa };

/// "auto", "window", "headless", "egl", "osmesa".
const char* backendName(Backend backend);

/// The EGL devices in EGL's order ("/dev/dri/renderD128", "GPU", "software (software)"); empty
/// where the build has no EGL or EGL enumerates none. ContextSpec::gpu indexes this list.
std::vector<std::string> eglDevices();

class GlContext;

struct ContextSpec {
  Backend backend = Backend::Auto;
  int width = 1280;
  int height = 720;
  std::string title = "liveprobe";
  bool vsync = true;
  /// The framebuffer's size when Auto comes up headless (0: width x height).
  int headlessWidth = 0, headlessHeight = 0;
  /// EGL: the device to open (an index of eglDevices()); -1 takes the first GPU.
  int gpu = -1;
  /// EGL: a context whose objects (buffers, textures, fences) the new one shares, as another
  /// thread's context shares the drawing one's: an EGL context on the same device (gpu), else a
  /// ContextError.
  const GlContext* shareWith = nullptr;
};

/// What a platform provides for liveprobe to draw into (as Filament's OpenGLPlatform): a current
/// context, a framebuffer and, for a window, its events; five calls. What a context is (headless
/// or a window, its name) is data, set once by the backend. Input and the title are the app's,
/// through GLFW's own calls on window().
class GlContext {
 public:
  virtual ~GlContext() = default;
  virtual void makeCurrent() = 0;
  /// Shows the frame (window) or does nothing (headless).
  virtual void present() = 0;
  virtual glm::ivec2 framebufferSize() const = 0;
  /// Whether the window was asked to close (its close button, or the app); never headless.
  virtual bool shouldClose() const = 0;
  /// Processes the window's pending events (a headless context has none).
  virtual void pollEvents() = 0;

  /// The GLFW window (for the app's input and Dear ImGui's GLFW backend); nullptr headless.
  GLFWwindow* window() const { return window_; }
  bool isHeadless() const { return window_ == nullptr; }
  /// "GLFW window", "EGL device 0, /dev/dri/renderD128" or "OSMesa offscreen", plus
  /// GL_RENDERER and GL_VERSION.
  const std::string& describe() const { return description_; }
  /// Which backend opened it (Window, Egl or OsMesa), and for EGL the device's index in
  /// eglDevices() (-1: Mesa's surfaceless platform).
  Backend backend() const { return backend_; }
  int device() const { return device_; }

 protected:
  GlContext() = default;
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;
  GLFWwindow* window_ = nullptr;  ///< set by the window backend
  std::string description_;       ///< set by each backend once GL is loaded
  Backend backend_ = Backend::Auto;
  int device_ = -1;
};

/// Whether a GL_RENDERER string (or a describe() holding one) names a software rasterizer
/// (llvmpipe, softpipe, swrast, SwiftShader): no GPU, no GPU timer.
bool isSoftwareRenderer(std::string_view renderer);

/// Creates a context and loads GL into it. Throws ContextError with the cause.
std::unique_ptr<GlContext> createGlContext(const ContextSpec& spec);

/// Makes no context current on this thread (a GLFW window's, an EGL one's), so that another
/// thread can make it current, or so that one of the other API can be made current here (GLX
/// and EGL contexts are not current on one thread together). makeCurrent() takes it up again.
void releaseCurrentContext();

}  // namespace lp::gl
