#pragma once
// The GL context backends behind createGlContext() (context_factory.cpp), one file each: the
// GLFW window (glfw_context.cpp, built with LIVEPROBE_WITH_GLFW) and OSMesa offscreen
// (osmesa_context.cpp). Only those two files include GLFW or OSMesa.
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

/// An offscreen context of spec.width x spec.height (Mesa llvmpipe).
std::unique_ptr<GlContext> openOffscreen(const ContextSpec& spec);

}  // namespace lp::gl
