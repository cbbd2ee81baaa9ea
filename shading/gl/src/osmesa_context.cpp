// OSMesa offscreen (Mesa llvmpipe): the one file of liveprobe::gl that includes OSMesa.
// clang-format off: glad's header must come first, standing in for <GL/gl.h>.
#include "liveprobe/gl/gl.h"
// clang-format on

#include <GL/osmesa.h>

#include <vector>

#include "context_backends.h"

namespace lp::gl {

namespace {

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
    description_ = "OSMesa offscreen (" + rendererString() + ")";
    backend_ = Backend::OsMesa;
  }
  ~OsMesaContext() override { OSMesaDestroyContext(ctx_); }
  void makeCurrent() override {
    if (!OSMesaMakeCurrent(ctx_, buffer_.data(), GL_UNSIGNED_BYTE, width_, height_))
      throw ContextError("OSMesa: cannot make the context current");
  }
  void present() override {}
  glm::ivec2 framebufferSize() const override { return {width_, height_}; }
  bool shouldClose() const override { return false; }
  void pollEvents() override {}

 private:
  OSMesaContext ctx_ = nullptr;
  int width_, height_;
  std::vector<unsigned char> buffer_;
};

}  // namespace

std::unique_ptr<GlContext> openOffscreen(const ContextSpec& spec, std::string&) {
  return std::make_unique<OsMesaContext>(spec);
}

}  // namespace lp::gl
