// What the app hands to GL: the context, the model, the lighting and the background.
#include "scene_gl.h"

#include <stdexcept>

#include "liveprobe/sh/error.h"

namespace lp::cli {

namespace {
gl::BackgroundMapping backgroundMapping(Layout drawn) {
  if (drawn != Layout::Equirect && drawn != Layout::Angular)
    throw std::logic_error("the background is drawn from an equirect or an angular map");
  return drawn == Layout::Angular ? gl::BackgroundMapping::Angular
                                  : gl::BackgroundMapping::Equirect;
}
}  // namespace

void setBackground(gl::Renderer& r, const Background& b) {
  if (b.raw)
    r.setBackgroundSrgb8(b.raw->bgr8.data(), b.raw->width, b.raw->height,
                         backgroundMapping(b.layout), b.scale);
  else if (b.image)
    r.setBackground(b.image->rgb.data(), b.image->width, b.image->height,
                    backgroundMapping(b.layout), b.scale);
  else if (b.onGpu)
    r.setBackground(*b.onGpu, backgroundMapping(b.layout), b.scale);
}

gl::Backend glBackend(const SceneSettings& sc) {
  if (sc.gl != gl::Backend::Auto) return sc.gl;
  return sc.headless ? gl::Backend::Headless : gl::Backend::Auto;
}

std::unique_ptr<gl::GlContext> openContext(gl::Backend backend, std::pair<int, int> size,
                                           std::pair<int, int> headlessSize, int gpu) {
  try {
    return gl::createGlContext({backend, size.first, size.second, "liveprobe", true,
                                headlessSize.first, headlessSize.second, gpu});
  } catch (const gl::ContextError& e) {
    throw Error(std::string("GL context: ") + e.what());
  }
}

void loadModel(gl::Renderer& r, const Mesh& mesh) {
  r.setMesh(mesh);
  if (!mesh.albedoTexture.empty()) {
    const Image tex = loadImage(mesh.albedoTexture);
    r.setAlbedoTexture(tex.rgb.data(), tex.width, tex.height);
  }
}

void loadLighting(gl::Renderer& r, const Lighting& lighting) {
  r.setLighting(lighting.radiance, lighting.lights);
  r.setEnvOrientation(lighting.orientation);
  setBackground(r, lighting.background);
}

}  // namespace lp::cli
