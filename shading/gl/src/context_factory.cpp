// The factory that picks a context backend (as Filament's PlatformFactory does): a window where
// a display opens and the build has one, OSMesa offscreen otherwise.
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

#if !LIVEPROBE_WITH_GLFW
std::unique_ptr<GlContext> openWindow(const ContextSpec&, std::string& whyNot) {
  whyNot = "this liveprobe was built without the GLFW window";
  return nullptr;
}
#endif

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
    std::string whyNot;
    if (auto window = openWindow(spec, whyNot)) return window;
    if (spec.backend == Backend::Window)
      throw ContextError("cannot open a window (" + whyNot + ")");
    // A display was named but cannot be used: say why before drawing headless.
    if (LIVEPROBE_WITH_GLFW && (std::getenv("DISPLAY") || std::getenv("WAYLAND_DISPLAY")))
      std::fprintf(stderr, "liveprobe: warning: no window on the display (%s): drawing headless\n",
                   whyNot.c_str());
    if (spec.headlessWidth > 0 && spec.headlessHeight > 0) {
      ContextSpec headless = spec;
      headless.width = spec.headlessWidth, headless.height = spec.headlessHeight;
      checkSize(headless.width, headless.height);
      return openOffscreen(headless);
    }
  }
  return openOffscreen(spec);
}

}  // namespace lp::gl
