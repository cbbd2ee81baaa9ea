// Headless GL through EGL: the one file of liveprobe::gl that includes EGL. A GPU is chosen
// with EGL_EXT_device_enumeration and opened on the device platform (EGL_EXT_platform_device);
// where no device platform is offered, Mesa's surfaceless platform serves. The context has no
// surface (EGL_KHR_surfaceless_context): it draws into a framebuffer object of its own, bound
// whenever it is made current (as Magnum's WindowlessEglApplication does).
// clang-format off: glad's header must come first, standing in for <GL/gl.h>.
#include "liveprobe/gl/gl.h"
// clang-format on

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <vector>

#include "context_backends.h"
#include "liveprobe/gl/handles.h"

namespace lp::gl {

namespace {

std::string eglErrorName(EGLint e) {
  switch (e) {
    case EGL_SUCCESS:
      return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
      return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
      return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE:
      return "EGL_BAD_SURFACE";
    default:
      return "EGL error 0x" + [e] {
        char b[16];
        std::snprintf(b, sizeof b, "%x", unsigned(e));
        return std::string(b);
      }();
  }
}

ContextError eglFailure(const std::string& what) {
  return ContextError("EGL: " + what + " (" + eglErrorName(eglGetError()) + ")");
}

bool hasExtension(const char* list, const char* name) {
  if (!list) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)); p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

template <typename F>
F proc(const char* name) {
  return reinterpret_cast<F>(eglGetProcAddress(name));
}

struct Device {
  EGLDeviceEXT handle;
  bool software;
  std::string name;  ///< the DRM node, or the driver's word for it
};

/// Mesa's libEGL prints its own warnings ("libEGL warning: egl: failed to create dri2 screen")
/// beside the one line liveprobe gives for the same failure: only fatal ones, unless the user
/// set EGL_LOG_LEVEL. Before the first EGL call, on the thread that opens the context.
void quietDriverLog() { ::setenv("EGL_LOG_LEVEL", "fatal", 0); }

std::vector<Device> listDevices() {
  quietDriverLog();
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!hasExtension(client, "EGL_EXT_device_enumeration") &&
      !hasExtension(client, "EGL_EXT_device_base"))
    return {};
  auto query = proc<PFNEGLQUERYDEVICESEXTPROC>("eglQueryDevicesEXT");
  auto string = proc<PFNEGLQUERYDEVICESTRINGEXTPROC>("eglQueryDeviceStringEXT");
  if (!query || !string) return {};
  EGLint count = 0;
  if (!query(0, nullptr, &count) || count <= 0) return {};
  std::vector<EGLDeviceEXT> handles(static_cast<std::size_t>(count));
  if (!query(count, handles.data(), &count)) return {};
  std::vector<Device> out;
  for (EGLint i = 0; i < count; ++i) {
    const char* ext = string(handles[std::size_t(i)], EGL_EXTENSIONS);
    Device d{handles[std::size_t(i)], hasExtension(ext, "EGL_MESA_device_software"), ""};
    if (hasExtension(ext, "EGL_EXT_device_drm"))
      if (const char* node = string(d.handle, EGL_DRM_DEVICE_FILE_EXT)) d.name = node;
    if (d.name.empty()) d.name = d.software ? "software" : "GPU";
    out.push_back(d);
  }
  return out;
}

/// A device's display is one EGLDisplay for the whole process, however many contexts it has
/// (a drawing context and the capture thread's): initialised by the first, terminated when the
/// last goes, as EGL_KHR_display_reference would count it. Never destroyed: a context held in a
/// static is destroyed after any function's static.
std::mutex& displayMutex() {
  static auto* m = new std::mutex;
  return *m;
}
std::map<EGLDisplay, int>& displayUsers() {
  static auto* users = new std::map<EGLDisplay, int>;
  return *users;
}
bool initialiseDisplay(EGLDisplay display) {
  std::lock_guard lock(displayMutex());
  int& users = displayUsers()[display];
  EGLint major = 0, minor = 0;
  if (users == 0 && !eglInitialize(display, &major, &minor)) {
    displayUsers().erase(display);
    return false;
  }
  ++users;
  return true;
}
void terminateDisplay(EGLDisplay display) {
  std::lock_guard lock(displayMutex());
  if (--displayUsers()[display] > 0) return;
  displayUsers().erase(display);
  eglTerminate(display);
}

class EglContext final : public GlContext {
 public:
  /// `share`: the context whose objects it shares (EGL_NO_CONTEXT: none). `borrowed`: the
  /// display is another's (a window's), initialised and terminated by it.
  EglContext(EGLDisplay display, std::string platform, const ContextSpec& spec, int device,
             EGLContext share = EGL_NO_CONTEXT, bool borrowed = false)
      : display_(display),
        platform_(std::move(platform)),
        width_(spec.width),
        height_(spec.height),
        borrowed_(borrowed) {
    if (!borrowed_ && !initialiseDisplay(display_))
      throw eglFailure("cannot initialise the display");
    try {
      if (share == EGL_NO_CONTEXT && spec.shareWith) share = sharedContext(*spec.shareWith);
      open(share);
      description_ = "EGL " + platform_ + " (" + rendererString() + ")";
      backend_ = Backend::Egl, device_ = device;
    } catch (...) {
      if (!borrowed_) terminateDisplay(display_);
      throw;
    }
  }
  ~EglContext() override {
    // Its objects are deleted in it: made current here where another thread released it, and
    // the context current here before (another of this process's) made current again after.
    const EGLContext before = eglGetCurrentContext();
    const bool mine = before == context_;
    const EGLDisplay beforeDisplay = eglGetCurrentDisplay();
    const EGLSurface draw = eglGetCurrentSurface(EGL_DRAW), read = eglGetCurrentSurface(EGL_READ);
    if (mine || eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      fbo_ = {}, colour_ = {}, depth_ = {};
    else
      (void)fbo_.release(), (void)colour_.release(), (void)depth_.release();
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    if (!mine && before != EGL_NO_CONTEXT) eglMakeCurrent(beforeDisplay, draw, read, before);
    if (!borrowed_) terminateDisplay(display_);
    if (mine || before == EGL_NO_CONTEXT)
      eglReleaseThread();  // the thread's EGL state (its current API, its last error) too
  }
  void makeCurrent() override {
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      throw eglFailure("cannot make the context current");
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
  }
  void present() override {}
  glm::ivec2 framebufferSize() const override { return {width_, height_}; }
  bool shouldClose() const override { return false; }
  void pollEvents() override {}

 private:
  /// The EGL context of `with`, checked to be on this display.
  EGLContext sharedContext(const GlContext& with) const {
    const auto* egl = dynamic_cast<const EglContext*>(&with);
    if (!egl || egl->display_ != display_)
      throw ContextError("EGL: a context shares objects only with an EGL context on its device (" +
                         with.describe() + " is not one)");
    return egl->context_;
  }
  void open(EGLContext share) {
    if (!hasExtension(eglQueryString(display_, EGL_EXTENSIONS), "EGL_KHR_surfaceless_context"))
      throw ContextError("EGL: the display has no EGL_KHR_surfaceless_context");
    if (!eglBindAPI(EGL_OPENGL_API)) throw eglFailure("no desktop OpenGL");
    // A pbuffer-capable config (the surface type defaults to windows, which no headless display
    // has); where there is none, no config at all (EGL_KHR_no_config_context).
    const EGLint configAttribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                    EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig config = EGL_NO_CONFIG_KHR;
    EGLint found = 0;
    if ((!eglChooseConfig(display_, configAttribs, &config, 1, &found) || found == 0) &&
        !hasExtension(eglQueryString(display_, EGL_EXTENSIONS), "EGL_KHR_no_config_context"))
      throw eglFailure("no OpenGL config");
    if (found == 0) config = EGL_NO_CONFIG_KHR;
    // The newest core profile offered: 4.6 down to 3.3 (compute needs 4.3).
    for (const auto& [maj, min] : {std::pair{4, 6}, {4, 5}, {4, 3}, {3, 3}}) {
      const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                maj,
                                EGL_CONTEXT_MINOR_VERSION,
                                min,
                                EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                EGL_NONE};
      context_ = eglCreateContext(display_, config, share, attribs);
      if (context_ != EGL_NO_CONTEXT) break;
    }
    if (context_ == EGL_NO_CONTEXT) throw eglFailure("cannot create a GL 3.3 core context");
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) {
      eglDestroyContext(display_, context_);
      throw eglFailure("cannot make the context current");
    }
    if (!gladLoadGL(reinterpret_cast<GLADloadfunc>(eglGetProcAddress))) {
      eglDestroyContext(display_, context_);
      throw ContextError("EGL: cannot load GL 3.3 core functions");
    }
    makeFramebuffer();
  }
  void makeFramebuffer() {
    GLuint id = 0;
    glGenRenderbuffers(1, &id);
    colour_.reset(id);
    glBindRenderbuffer(GL_RENDERBUFFER, id);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width_, height_);
    glGenRenderbuffers(1, &id);
    depth_.reset(id);
    glBindRenderbuffer(GL_RENDERBUFFER, id);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH24_STENCIL8, width_, height_);
    glGenFramebuffers(1, &id);
    fbo_.reset(id);
    glBindFramebuffer(GL_FRAMEBUFFER, id);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, colour_.get());
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER,
                              depth_.get());
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw ContextError("EGL: the " + std::to_string(width_) + "x" + std::to_string(height_) +
                         " framebuffer is incomplete");
    glViewport(0, 0, width_, height_);
  }

  EGLDisplay display_;
  EGLContext context_ = EGL_NO_CONTEXT;
  std::string platform_;
  int width_, height_;
  bool borrowed_;
  Framebuffer fbo_;
  Renderbuffer colour_, depth_;
};

}  // namespace

void releaseEglContext() {
  if (eglGetCurrentContext() == EGL_NO_CONTEXT) return;
  eglMakeCurrent(eglGetCurrentDisplay(), EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglReleaseThread();
}

std::vector<std::string> eglDevices() {
  std::vector<std::string> out;
  for (const Device& d : listDevices())
    out.push_back(d.name + (d.software && d.name != "software" ? " (software)" : ""));
  return out;
}

std::unique_ptr<GlContext> openEgl(const ContextSpec& spec, bool hardwareOnly,
                                   std::string& whyNot) {
  quietDriverLog();
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!client) {
    whyNot = "EGL has no client extensions (no EGL 1.5 driver)";
    return nullptr;
  }
  auto getDisplay = proc<PFNEGLGETPLATFORMDISPLAYEXTPROC>("eglGetPlatformDisplayEXT");
  if (!getDisplay) {
    whyNot = "EGL has no eglGetPlatformDisplayEXT";
    return nullptr;
  }
  // Sharing a window's objects: on the window's own display.
  if (spec.shareWith && spec.shareWith->backend() == Backend::Window) {
    const WindowEgl w = windowEgl(*spec.shareWith);
    if (!w.display)
      throw ContextError("EGL: the window's context is not EGL's (" + spec.shareWith->describe() +
                         "): it shares nothing with an EGL context");
    return std::make_unique<EglContext>(EGLDisplay(w.display), "the window's display", spec, -1,
                                        EGLContext(w.context), true);
  }
  const std::vector<Device> devices =
      hasExtension(client, "EGL_EXT_platform_device") ? listDevices() : std::vector<Device>{};
  if (spec.gpu >= 0) {
    if (std::size_t(spec.gpu) >= devices.size())
      throw ContextError("EGL: no device " + std::to_string(spec.gpu) + " (" +
                         std::to_string(devices.size()) + " found)");
    const Device& d = devices[std::size_t(spec.gpu)];
    EGLDisplay dpy = getDisplay(EGL_PLATFORM_DEVICE_EXT, d.handle, nullptr);
    if (dpy == EGL_NO_DISPLAY) throw eglFailure("no display on device " + std::to_string(spec.gpu));
    return std::make_unique<EglContext>(dpy, "device " + std::to_string(spec.gpu) + ", " + d.name,
                                        spec, spec.gpu);
  }
  // The first device that opens: a GPU, then (unless only hardware will do) a software one.
  const auto firstDevice = [&](bool software) -> std::unique_ptr<GlContext> {
    for (std::size_t i = 0; i < devices.size(); ++i) {
      if (devices[i].software != software) continue;
      EGLDisplay dpy = getDisplay(EGL_PLATFORM_DEVICE_EXT, devices[i].handle, nullptr);
      if (dpy != EGL_NO_DISPLAY)
        return std::make_unique<EglContext>(
            dpy, "device " + std::to_string(i) + ", " + devices[i].name, spec, int(i));
    }
    return nullptr;
  };
  if (auto gpu = firstDevice(false)) return gpu;
  if (hardwareOnly) {
    whyNot = devices.empty() ? "EGL offers no device" : "EGL finds no GPU, only a software device";
    return nullptr;
  }
  if (auto software = firstDevice(true)) return software;
  if (hasExtension(client, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay dpy = getDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (dpy != EGL_NO_DISPLAY) return std::make_unique<EglContext>(dpy, "surfaceless", spec, -1);
  }
  whyNot = "EGL offers neither a device nor the surfaceless platform";
  return nullptr;
}

}  // namespace lp::gl
