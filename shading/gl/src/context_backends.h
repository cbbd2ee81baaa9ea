#pragma once
// The GL context backends behind createGlContext() (context_factory.cpp), one file each: the
// GLFW window (glfw_context.cpp, built with LIVEPROBE_WITH_GLFW), EGL headless
// (egl_context.cpp, LIVEPROBE_WITH_EGL) and OSMesa offscreen (osmesa_context.cpp,
// LIVEPROBE_WITH_OSMESA). Only those three files include GLFW, EGL or OSMesa.
#include <memory>
#include <string>

#include "liveprobe/gl/context.h"

namespace lp::gl {

/// "GL_RENDERER, GL VERSION" of the current context.
std::string rendererString();

/// A window on the display, or nullptr with the reason in `whyNot` when no display can be used
/// (none named, or GLFW cannot open it). Throws ContextError when the display opens but the
/// window or its GL cannot be made.
std::unique_ptr<GlContext> openWindow(const ContextSpec& spec, std::string& whyNot);

/// A surfaceless EGL context drawing into a spec.width x spec.height framebuffer object of its
/// own: on device spec.gpu, else the first GPU, else (unless `hardwareOnly`) a software device or
/// Mesa's surfaceless platform. nullptr with the reason in `whyNot` when EGL has none of these;
/// throws ContextError when the one chosen fails.
std::unique_ptr<GlContext> openEgl(const ContextSpec& spec, bool hardwareOnly, std::string& whyNot);

/// A window's EGL display and context (EGLDisplay, EGLContext: this header includes no EGL),
/// for a context that shares its objects (ContextSpec::shareWith); null where the window's
/// context is not EGL's (GLX) or `window` is not a window.
struct WindowEgl {
  void* display = nullptr;
  void* context = nullptr;
};
WindowEgl windowEgl(const GlContext& window);

/// Makes no window's context (releaseWindowContext) or EGL context (releaseEglContext) current
/// on this thread; nothing where the build has none.
void releaseWindowContext();
void releaseEglContext();

/// An offscreen context of spec.width x spec.height (Mesa llvmpipe), or nullptr with the reason
/// in `whyNot` where the build has no OSMesa.
std::unique_ptr<GlContext> openOffscreen(const ContextSpec& spec, std::string& whyNot);

}  // namespace lp::gl
