// The factory that picks a context backend (as Filament's PlatformFactory does): a window where
// a display opens and the build has one; headless, EGL on a GPU where EGL finds one, else OSMesa
// (Mesa's llvmpipe on the CPU).
// clang-format off: glad's header must come first, standing in for <GL/gl.h>.
#include "liveprobe/gl/gl.h"
// clang-format on

#include <cstdio>
#include <cstdlib>
#include <string>

#include "context_backends.h"
#include "liveprobe/backends.h"
#include "liveprobe/gl/context.h"

namespace lp::gl {

std::string rendererString() {
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return std::string(r ? r : "?") + ", GL " + (v ? v : "?");
}

bool isSoftwareRenderer(std::string_view renderer) {
  for (std::string_view name : {"llvmpipe", "softpipe", "SwiftShader", "swrast"})
    if (renderer.find(name) != std::string_view::npos) return true;
  return false;
}

const char* backendName(Backend backend) {
  switch (backend) {
    case Backend::Auto:
      return "auto";
    case Backend::Window:
      return "window";
    case Backend::Headless:
      return "headless";
    case Backend::Egl:
      return "egl";
    case Backend::OsMesa:
      return "osmesa";
  }
  return "?";
}

void releaseCurrentContext() {
  releaseWindowContext();
  releaseEglContext();
}

#if !LIVEPROBE_WITH_GLFW
WindowEgl windowEgl(const GlContext&) { return {}; }
std::unique_ptr<GlContext> openWindow(const ContextSpec&, std::string& whyNot) {
  whyNot = "this liveprobe was built without the GLFW window (LIVEPROBE_WITH_GLFW)";
  return nullptr;
}
void releaseWindowContext() {}
#endif
#if !LIVEPROBE_WITH_EGL
void releaseEglContext() {}
std::vector<std::string> eglDevices() { return {}; }
std::unique_ptr<GlContext> openEgl(const ContextSpec&, bool, std::string& whyNot) {
  whyNot = "this liveprobe was built without EGL (LIVEPROBE_WITH_EGL)";
  return nullptr;
}
#endif
#if !LIVEPROBE_WITH_OSMESA
std::unique_ptr<GlContext> openOffscreen(const ContextSpec&, std::string& whyNot) {
  whyNot = "this liveprobe was built without OSMesa (LIVEPROBE_WITH_OSMESA)";
  return nullptr;
}
#endif

namespace {

void checkSize(int width, int height) {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
    throw ContextError("bad framebuffer size " + std::to_string(width) + "x" +
                       std::to_string(height));
}

/// EGL on a GPU, else OSMesa; EGL on a software device only where the build has no OSMesa.
std::unique_ptr<GlContext> openHeadless(const ContextSpec& spec) {
  std::string eglWhy, osmesaWhy;
  if (auto egl = openEgl(spec, /*hardwareOnly=*/LIVEPROBE_WITH_OSMESA, eglWhy)) return egl;
  if (auto osmesa = openOffscreen(spec, osmesaWhy)) return osmesa;
  throw ContextError("no headless GL: " + eglWhy + "; " + osmesaWhy);
}

}  // namespace

std::unique_ptr<GlContext> createGlContext(const ContextSpec& spec) {
  checkSize(spec.width, spec.height);
  if (spec.shareWith && spec.backend != Backend::Egl)
    throw ContextError(std::string("a context shares objects only as EGL (asked: ") +
                       backendName(spec.backend) + ")");
  std::string whyNot;
  switch (spec.backend) {
    case Backend::Egl:
      if (auto egl = openEgl(spec, false, whyNot)) return egl;
      throw ContextError("cannot open EGL (" + whyNot + ")");
    case Backend::OsMesa:
      if (auto osmesa = openOffscreen(spec, whyNot)) return osmesa;
      throw ContextError("cannot open OSMesa (" + whyNot + ")");
    case Backend::Headless:
      return openHeadless(spec);
    case Backend::Window:
    case Backend::Auto:
      break;
  }
  if (auto window = openWindow(spec, whyNot)) return window;
  if (spec.backend == Backend::Window) throw ContextError("cannot open a window (" + whyNot + ")");
  // A display was named but cannot be used: say why before drawing headless.
  if (LIVEPROBE_WITH_GLFW && (std::getenv("DISPLAY") || std::getenv("WAYLAND_DISPLAY")))
    std::fprintf(stderr, "liveprobe: warning: no window on the display (%s): drawing headless\n",
                 whyNot.c_str());
  if (spec.headlessWidth > 0 && spec.headlessHeight > 0) {
    ContextSpec headless = spec;
    headless.width = spec.headlessWidth, headless.height = spec.headlessHeight;
    checkSize(headless.width, headless.height);
    return openHeadless(headless);
  }
  return openHeadless(spec);
}

}  // namespace lp::gl
