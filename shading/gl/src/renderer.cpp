#include "liveprobe/gl/renderer.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <stdexcept>
#include <string>

#include "liveprobe/gl/context.h"
#include "liveprobe/sh/axes.h"
#include "programs.h"
#include "shaders.h"

namespace lp::gl {

void checkGl(const char* where) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR)
    throw ContextError(std::string(where) + ": GL error 0x" + [e] {
      char b[16];
      std::snprintf(b, sizeof b, "%04x", e);
      return std::string(b);
    }());
}

glm::vec3 Camera::eye() const {
  const float y = glm::radians(yawDeg), p = glm::radians(pitchDeg);
  return distance * glm::vec3(std::cos(p) * std::sin(y), std::sin(p), std::cos(p) * std::cos(y));
}
glm::mat4 Camera::view() const { return glm::lookAt(eye(), glm::vec3(0.0f), glm::vec3(0, 1, 0)); }
glm::mat4 Camera::projection(float aspect) const {
  const float w = frame.z - frame.x, h = frame.w - frame.y;
  if (w >= 1.0f && h >= 1.0f) return glm::perspective(glm::radians(fovYDeg), aspect, 0.05f, 100.0f);
  const float partAspect = aspect * w / h;
  float fovY = glm::radians(fovYDeg);
  if (partAspect < 1.0f) fovY = 2.0f * std::atan(std::tan(fovY / 2) / partAspect);
  // The part's clip space into the frame's: x' = w x + (x0 + x1 - 1) w_clip, likewise y.
  glm::mat4 toFrame(1.0f);
  toFrame[0][0] = w;
  toFrame[1][1] = h;
  toFrame[3][0] = frame.x + frame.z - 1.0f;
  toFrame[3][1] = frame.y + frame.w - 1.0f;
  return toFrame * glm::perspective(fovY, partAspect, 0.05f, 100.0f);
}

namespace {

GLint loc(const Program& p, const char* name) { return glGetUniformLocation(p.get(), name); }

// GL's rows start at the bottom; images here start at the top.
template <class T>
void flipRows(std::vector<T>& px, std::size_t row, int rows) {
  for (int y = 0; y < rows / 2; ++y)
    std::swap_ranges(px.begin() + std::ptrdiff_t(y * row),
                     px.begin() + std::ptrdiff_t((y + 1) * row),
                     px.begin() + std::ptrdiff_t((rows - 1 - y) * row));
}

template <class T>
Buffer upload(GLenum target, const std::vector<T>& data) {
  GLuint id = 0;
  glGenBuffers(1, &id);
  Buffer b(id);
  glBindBuffer(target, id);
  glBufferData(target, GLsizeiptr(data.size() * sizeof(T)), data.data(), GL_STATIC_DRAW);
  return b;
}

// A bound, linearly filtered 2D texture: internal format, client format and type as given.
Texture makeTexture(GLint internal, int width, int height, GLenum format, GLenum type,
                    const void* data, GLint wrapS) {
  GLuint id = 0;
  glGenTextures(1, &id);
  Texture t(id);
  glBindTexture(GL_TEXTURE_2D, id);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, internal, width, height, 0, format, type, data);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, wrapS);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  checkGl("uploading a texture");
  return t;
}

Texture makeFloatTexture(const float* rgb, int width, int height, GLint wrapS) {
  return makeTexture(GL_RGB32F, width, height, GL_RGB, GL_FLOAT, rgb, wrapS);
}

}  // namespace

FloatTarget::FloatTarget(int width, int height) : width_(width), height_(height) {
  GLint previous = 0;  // the context's own framebuffer (EGL's is not 0)
  glGetIntegerv(GL_FRAMEBUFFER_BINDING, &previous);
  GLuint id = 0;
  glGenFramebuffers(1, &id);
  fbo_.reset(id);
  glGenTextures(1, &id);
  colour_.reset(id);
  glBindTexture(GL_TEXTURE_2D, id);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, width, height, 0, GL_RGBA, GL_FLOAT, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glGenRenderbuffers(1, &id);
  depth_.reset(id);
  glBindRenderbuffer(GL_RENDERBUFFER, id);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, colour_.get(), 0);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_.get());
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw ContextError("float framebuffer is incomplete");
  glBindFramebuffer(GL_FRAMEBUFFER, GLuint(previous));
}

void FloatTarget::bind() const { glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get()); }

std::vector<float> FloatTarget::readRgba() const {
  bind();
  std::vector<float> px(std::size_t(width_) * height_ * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_FLOAT, px.data());
  flipRows(px, std::size_t(width_) * 4, height_);
  return px;
}

namespace {
/// A shader source with `#define NAME` after its #version line.
std::string withDefine(const char* source, const std::string& name) {
  std::string s(source);
  s.insert(s.find('\n') + 1, "#define " + name + "\n");
  return s;
}
}  // namespace

Renderer::Renderer()
    : modelProgram_(linkProgram(shaders::kModelVs, shaders::kModelFs, "model shader")),
      modelLitProgram_(linkProgram(shaders::kModelVs,
                                   withDefine(shaders::kModelFs, "LP_LIGHTS").c_str(),
                                   "model shader with lights")),
      modelShadowProgram_(linkProgram(
          shaders::kModelVs,
          withDefine(withDefine(shaders::kModelFs, "LP_LIGHTS").c_str(), "LP_SHADOWS").c_str(),
          "model shader with shadows")),
      backgroundProgram_(
          linkProgram(shaders::kBackgroundVs, shaders::kBackgroundFs, "background shader")),
      probeProgram_(linkProgram(shaders::kBackgroundVs, shaders::kProbeFs, "probe view shader")),
      depthProgram_(linkProgram(shaders::kDepthVs, shaders::kDepthFs, "shadow depth shader")),
      groundProgram_(linkProgram(shaders::kGroundVs, shaders::kGroundFs, "ground shader")),
      groundShadowProgram_(linkProgram(shaders::kGroundVs,
                                       withDefine(shaders::kGroundFs, "LP_SHADOWS").c_str(),
                                       "ground shader with shadows")) {
  GLuint id = 0;
  glGenVertexArrays(1, &id);
  emptyVao_.reset(id);
  glGenVertexArrays(1, &id);
  meshVao_.reset(id);
  checkGl("Renderer()");
}

void Renderer::setMesh(const Mesh& mesh) {
  glBindVertexArray(meshVao_.get());
  positions_ = upload(GL_ARRAY_BUFFER, mesh.positions);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  normals_ = upload(GL_ARRAY_BUFFER, mesh.normals);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  hasUv_ = mesh.uvs.size() == mesh.positions.size();
  if (hasUv_) {
    uvs_ = upload(GL_ARRAY_BUFFER, mesh.uvs);
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  } else {
    uvs_.reset();
    glDisableVertexAttribArray(2);
    glVertexAttrib2f(2, 0.0f, 0.0f);
  }
  indices_ = upload(GL_ELEMENT_ARRAY_BUFFER, mesh.indices);
  indexCount_ = GLsizei(mesh.indices.size());
  // Bounding sphere (about the box's centre) and lowest point, for the shadow map and the ground.
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::vec3& p : mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  if (!mesh.positions.empty()) {
    const glm::vec3 c = 0.5f * (lo + hi);
    float r = 0.0f;
    for (const glm::vec3& p : mesh.positions) r = std::max(r, glm::length(p - c));
    bounds_ = glm::vec4(c, r);
    groundY_ = lo.y;
  }
  // The ground (--ground): a square 40 bounding radii wide at the model's lowest point.
  if (!groundVao_.isValid()) {
    GLuint id = 0;
    glGenVertexArrays(1, &id);
    groundVao_.reset(id);
  }
  const float g = 20.0f * bounds_.w, y = groundY_;
  const std::vector<glm::vec3> quad = {{-g, y, -g}, {g, y, -g}, {g, y, g},
                                       {-g, y, -g}, {g, y, g},  {-g, y, g}};
  glBindVertexArray(groundVao_.get());
  groundVertices_ = upload(GL_ARRAY_BUFFER, quad);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  albedo_ = mesh.albedo;
  glBindVertexArray(0);
  checkGl("Renderer::setMesh");
}

void Renderer::setAlbedoTexture(const float* rgb, int width, int height) {
  albedoTex_ = makeFloatTexture(rgb, width, height, GL_REPEAT);
}

void Renderer::setLighting(const Sh9& radiance) { setLighting(radiance, {}); }

void Renderer::setLighting(const Sh9& residual, const std::vector<Light>& lights) {
  sh_ = irradianceMatrices(residual);
  if (lights.size() > std::size_t(kMaxLights))
    throw std::invalid_argument(std::to_string(lights.size()) +
                                " lights; the shaders draw at most " + std::to_string(kMaxLights));
  lights_ = lights;
}

void Renderer::setIrradianceUniforms(const Program& program) const {
  glUniformMatrix4fv(loc(program, "uShR"), 1, GL_FALSE, glm::value_ptr(sh_[0]));
  glUniformMatrix4fv(loc(program, "uShG"), 1, GL_FALSE, glm::value_ptr(sh_[1]));
  glUniformMatrix4fv(loc(program, "uShB"), 1, GL_FALSE, glm::value_ptr(sh_[2]));
  glUniform1i(loc(program, "uLightCount"), int(lights_.size()));
  for (std::size_t i = 0; i < lights_.size(); ++i) {
    const std::string at = "[" + std::to_string(i) + "]";
    glUniform3fv(loc(program, ("uLightDir" + at).c_str()), 1, glm::value_ptr(lights_[i].dir));
    glUniform3fv(loc(program, ("uLightPower" + at).c_str()), 1, glm::value_ptr(lights_[i].power));
    const float a = lights_[i].angularRadius;
    glUniform3f(loc(program, ("uLightTrig" + at).c_str()), std::sin(a), std::cos(a),
                std::sin(0.5f * a));
  }
}

void Renderer::bindFloatBackground(int width, int height, BackgroundMapping mapping) {
  const GLint wrapS = mapping == BackgroundMapping::Equirect ? GL_REPEAT : GL_CLAMP_TO_EDGE;
  // A float texture of the size is written over (its wrap set for the mapping); else one is made.
  if (!backgroundTex_.isValid() || backgroundSrgb_ || width != backgroundW_ ||
      height != backgroundH_) {
    backgroundTex_ = makeFloatTexture(nullptr, width, height, wrapS);
  } else {
    glBindTexture(GL_TEXTURE_2D, backgroundTex_.get());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, wrapS);
  }
  backgroundW_ = width, backgroundH_ = height, backgroundSrgb_ = false;
}

void Renderer::setBackground(const float* rgb, int width, int height, BackgroundMapping mapping,
                             float displayScale) {
  bindFloatBackground(width, height, mapping);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGB, GL_FLOAT, rgb);
  checkGl("Renderer::setBackground");
  backgroundMapping_ = mapping;
  backgroundScale_ = 1.0f;
  backgroundDisplayScale_ = displayScale;
}

void Renderer::setBackground(const GpuImage& image, BackgroundMapping mapping, float scale) {
  const int w = image.width(), h = image.height();
  const bool copied = image.read([&](GLuint buffer) {
    bindFloatBackground(w, h, mapping);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, buffer);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RGB, GL_FLOAT, nullptr);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  });
  checkGl("Renderer::setBackground (a frame kept on the GPU)");
  if (!copied) return;
  backgroundMapping_ = mapping;
  backgroundScale_ = scale;
  backgroundDisplayScale_ = 0.0f;
}

void Renderer::setBackgroundSrgb8(const std::uint8_t* bgr, int width, int height,
                                  BackgroundMapping mapping, float scale) {
  // Re-specify only when the size changes; otherwise update the texels in place.
  if (!backgroundTex_.isValid() || !backgroundSrgb_ || width != backgroundW_ ||
      height != backgroundH_) {
    backgroundTex_ =
        makeTexture(GL_SRGB8, width, height, GL_BGR, GL_UNSIGNED_BYTE, nullptr,
                    mapping == BackgroundMapping::Equirect ? GL_REPEAT : GL_CLAMP_TO_EDGE);
    backgroundW_ = width, backgroundH_ = height, backgroundSrgb_ = true;
  }
  glBindTexture(GL_TEXTURE_2D, backgroundTex_.get());
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_BGR, GL_UNSIGNED_BYTE, bgr);
  checkGl("Renderer::setBackgroundSrgb8");
  backgroundMapping_ = mapping;
  backgroundScale_ = scale;
}

void Renderer::setEnvOrientation(const glm::mat3& worldFromFile) {
  fileFromWorld_ = glm::transpose(worldFromFile);
}

void Renderer::bindPanorama(const Program& p, const ShadingSettings& s) const {
  glUniformMatrix3fv(loc(p, "uFileFromWorld"), 1, GL_FALSE, glm::value_ptr(fileFromWorld_));
  glUniform1f(loc(p, "uExposure"), s.exposure);
  glUniform1i(loc(p, "uToneMap"), int(s.toneMap));
  glUniform1f(loc(p, "uPanoramaScale"), backgroundScale_);
  const bool from8bit = backgroundSrgb_ || backgroundDisplayScale_ > 0;
  glUniform1i(loc(p, "uDisplayReferred"), from8bit && s.displayReferredBackground);
  glUniform1f(loc(p, "uDisplayDivide"),
              backgroundSrgb_ ? 1.0f : std::max(backgroundDisplayScale_, 1e-30f));
  glUniform1i(loc(p, "uMapping"), int(backgroundMapping_));
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, backgroundTex_.get());
  glUniform1i(loc(p, "uPanorama"), 0);
}

namespace {

/// An offscreen framebuffer of `size`: an RGBA8 colour and a 24-bit depth renderbuffer, with
/// `samples` samples per pixel (1: single-sampled). `what` names it in an error.
void makeRenderTarget(Framebuffer& fbo, Renderbuffer& colour, Renderbuffer& depth, glm::ivec2 size,
                      int samples, const std::string& what) {
  GLuint id = 0;
  glGenFramebuffers(1, &id);
  fbo.reset(id);
  auto storage = [&](Renderbuffer& rb, GLenum format) {
    glGenRenderbuffers(1, &id);
    rb.reset(id);
    glBindRenderbuffer(GL_RENDERBUFFER, id);
    if (samples > 1)
      glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, format, size.x, size.y);
    else
      glRenderbufferStorage(GL_RENDERBUFFER, format, size.x, size.y);
  };
  storage(colour, GL_RGBA8);
  storage(depth, GL_DEPTH_COMPONENT24);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo.get());
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, colour.get());
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth.get());
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw ContextError(what + " framebuffer is incomplete");
  checkGl(("Renderer: " + what + " target").c_str());
}

}  // namespace

void Renderer::ensureMultisample(glm::ivec2 size, int samples) {
  if (msaa_.fbo.isValid() && msaa_.size == size && msaa_.samples == samples) return;
  msaa_ = Target{};
  makeRenderTarget(msaa_.fbo, msaa_.colourMs, msaa_.depth, size, samples,
                   "multisample (" + std::to_string(samples) + " samples)");
  msaa_.size = size;
  msaa_.samples = samples;
}

void Renderer::ensureScaled(glm::ivec2 size) {
  if (scaled_.fbo.isValid() && scaled_.size == size) return;
  scaled_ = Target{};
  makeRenderTarget(scaled_.fbo, scaled_.colourMs, scaled_.depth, size, 1,
                   "scaled (" + std::to_string(size.x) + "x" + std::to_string(size.y) + ")");
  scaled_.size = size;
}

void Renderer::draw(glm::ivec2 size, const Camera& camera, const ShadingSettings& s) {
  if (!(s.renderScale < 1.0f) || s.output != OutputMode::Display) {
    drawView(size, camera, s);
    return;
  }
  // Dynamic resolution: the view at a fraction of the size, scaled up into the bound target.
  GLint out = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &out);
  const float scale = std::max(0.05f, s.renderScale);
  const glm::ivec2 inner = glm::max(glm::ivec2(1), glm::ivec2(glm::round(glm::vec2(size) * scale)));
  ensureScaled(inner);
  glBindFramebuffer(GL_FRAMEBUFFER, scaled_.fbo.get());
  drawView(inner, camera, s);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, scaled_.fbo.get());
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, GLuint(out));
  glBlitFramebuffer(0, 0, inner.x, inner.y, 0, 0, size.x, size.y, GL_COLOR_BUFFER_BIT, GL_LINEAR);
  glBindFramebuffer(GL_FRAMEBUFFER, GLuint(out));
  checkGl("Renderer::draw (scaled)");
}

void Renderer::drawView(glm::ivec2 size, const Camera& camera, const ShadingSettings& s) {
  GLint target = 0;
  const bool shadows = s.shadows && !lights_.empty() && indexCount_ > 0;
  if (shadows) {
    GLint bound = 0;
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &bound);
    renderShadowMap();
    glBindFramebuffer(GL_FRAMEBUFFER, GLuint(bound));
  }
  const bool multisample = s.samples > 1 && s.output == OutputMode::Display;
  if (multisample) {
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &target);
    ensureMultisample(size, s.samples);
    glBindFramebuffer(GL_FRAMEBUFFER, msaa_.fbo.get());
  }
  glViewport(0, 0, size.x, size.y);
  glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  const glm::mat4 viewProj =
      camera.projection(float(size.x) / float(std::max(1, size.y))) * camera.view();
  const glm::mat3 worldFromGl = axes::worldFromGlMatrix();

  if (s.background && backgroundTex_.isValid() && s.output == OutputMode::Display) {
    glDisable(GL_DEPTH_TEST);
    glUseProgram(backgroundProgram_.get());
    glUniformMatrix4fv(loc(backgroundProgram_, "uInvViewProj"), 1, GL_FALSE,
                       glm::value_ptr(glm::inverse(viewProj)));
    glUniformMatrix3fv(loc(backgroundProgram_, "uWorldFromGl"), 1, GL_FALSE,
                       glm::value_ptr(worldFromGl));
    bindPanorama(backgroundProgram_, s);
    glBindVertexArray(emptyVao_.get());
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  if (indexCount_ > 0) {
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    // The variant without the lights' loop when there is none (see shaders.cpp).
    const Program& model = shadows           ? modelShadowProgram_
                           : lights_.empty() ? modelProgram_
                                             : modelLitProgram_;
    glUseProgram(model.get());
    glUniformMatrix4fv(loc(model, "uViewProj"), 1, GL_FALSE, glm::value_ptr(viewProj));
    setIrradianceUniforms(model);
    setShadowUniforms(model, shadows);
    glUniformMatrix3fv(loc(model, "uWorldFromGl"), 1, GL_FALSE, glm::value_ptr(worldFromGl));
    glUniform3fv(loc(model, "uAlbedo"), 1, glm::value_ptr(albedo_));
    glUniform1i(loc(model, "uHasTexture"), albedoTex_.isValid() && hasUv_);
    glUniform1f(loc(model, "uExposure"), s.exposure);
    glUniform1i(loc(model, "uToneMap"), int(s.toneMap));
    glUniform1i(loc(model, "uOutput"), int(s.output));
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, albedoTex_.get());
    glUniform1i(loc(model, "uAlbedoTex"), 1);
    glBindVertexArray(meshVao_.get());
    glDrawElements(GL_TRIANGLES, indexCount_, GL_UNSIGNED_INT, nullptr);
  }
  if (s.ground && indexCount_ > 0 && s.output == OutputMode::Display)
    drawGround(viewProj, camera, s);
  glBindVertexArray(0);
  if (multisample) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, msaa_.fbo.get());
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, GLuint(target));
    glBlitFramebuffer(0, 0, size.x, size.y, 0, 0, size.x, size.y, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, GLuint(target));
  }
  checkGl("Renderer::drawView");
}

void Renderer::renderShadowMap() {
  if (!shadowFbo_.isValid()) {
    GLuint id = 0;
    glGenTextures(1, &id);
    shadowDepth_.reset(id);
    glBindTexture(GL_TEXTURE_2D, id);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT32F, kShadowSize, kShadowSize, 0,
                 GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glGenFramebuffers(1, &id);
    shadowFbo_.reset(id);
    glBindFramebuffer(GL_FRAMEBUFFER, id);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadowDepth_.get(),
                           0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
  }
  // An orthographic view along the light, covering the model and the ground around it (three
  // bounding radii each way).
  const glm::vec3 toLight = glm::normalize(axes::glFromWorld(lights_[0].dir));
  const glm::vec3 centre(bounds_),
      up = std::abs(toLight.y) > 0.99f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  const float half = 3.0f * bounds_.w, depth = 8.0f * bounds_.w;
  lightViewProj_ = glm::ortho(-half, half, -half, half, 0.0f, depth) *
                   glm::lookAt(centre + toLight * (0.5f * depth), centre, up);
  shadowTexelWorld_ = 2.0f * half / float(kShadowSize);
  shadowDepthRange_ = depth;
  glBindFramebuffer(GL_FRAMEBUFFER, shadowFbo_.get());
  glViewport(0, 0, kShadowSize, kShadowSize);
  glClear(GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glUseProgram(depthProgram_.get());
  glUniformMatrix4fv(loc(depthProgram_, "uLightViewProj"), 1, GL_FALSE,
                     glm::value_ptr(lightViewProj_));
  glBindVertexArray(meshVao_.get());
  glDrawElements(GL_TRIANGLES, indexCount_, GL_UNSIGNED_INT, nullptr);
  glBindVertexArray(0);
  checkGl("Renderer::renderShadowMap");
}

void Renderer::setShadowUniforms(const Program& program, bool on) const {
  glUniform1i(loc(program, "uShadows"), on);
  if (!on) return;
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_2D, shadowDepth_.get());
  glUniform1i(loc(program, "uShadowMap"), 2);
  glUniformMatrix4fv(loc(program, "uLightViewProj"), 1, GL_FALSE, glm::value_ptr(lightViewProj_));
  glUniform1f(loc(program, "uShadowTexel"), 1.0f / float(kShadowSize));
  glUniform1f(loc(program, "uShadowTexelWorld"), shadowTexelWorld_);
  glUniform1f(loc(program, "uShadowDepthRange"), shadowDepthRange_);
  glUniform1f(loc(program, "uTanRadius"), std::tan(lights_[0].angularRadius));
}

void Renderer::drawGround(const glm::mat4& viewProj, const Camera& camera,
                          const ShadingSettings& s) {
  glBindVertexArray(groundVao_.get());
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  const bool shadows = s.shadows && !lights_.empty();
  const Program& ground = shadows ? groundShadowProgram_ : groundProgram_;
  glUseProgram(ground.get());
  glUniformMatrix4fv(loc(ground, "uViewProj"), 1, GL_FALSE, glm::value_ptr(viewProj));
  glUniformMatrix3fv(loc(ground, "uWorldFromGl"), 1, GL_FALSE,
                     glm::value_ptr(axes::worldFromGlMatrix()));
  glUniform3fv(loc(ground, "uEye"), 1, glm::value_ptr(camera.eye()));
  glUniform4fv(loc(ground, "uOccluder"), 1, glm::value_ptr(bounds_));
  glUniform1i(loc(ground, "uHavePanorama"), backgroundTex_.isValid());
  glUniform1f(loc(ground, "uExposure"), s.exposure);
  glUniform1i(loc(ground, "uToneMap"), int(s.toneMap));
  setIrradianceUniforms(ground);
  setShadowUniforms(ground, shadows);
  bindPanorama(ground, s);
  glDrawArrays(GL_TRIANGLES, 0, 6);
  checkGl("Renderer::drawGround");
}

void Renderer::drawProbeViews(const Camera& camera, const ShadingSettings& s) {
  GLint target = 0, viewport[4];
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &target);
  glGetIntegerv(GL_VIEWPORT, viewport);
  const glm::ivec2 sizes[3] = {{256, 128}, {128, 128}, {128, 128}};
  const glm::mat3 worldFromView =
      axes::worldFromGlMatrix() * glm::transpose(glm::mat3(camera.view()));
  glDisable(GL_DEPTH_TEST);
  glUseProgram(probeProgram_.get());
  bindPanorama(probeProgram_, s);
  glUniform1i(loc(probeProgram_, "uHavePanorama"), backgroundTex_.isValid());
  glUniformMatrix3fv(loc(probeProgram_, "uWorldFromView"), 1, GL_FALSE,
                     glm::value_ptr(worldFromView));
  setIrradianceUniforms(probeProgram_);
  glBindVertexArray(emptyVao_.get());
  for (int v = 0; v < 3; ++v) {
    Target& t = probes_[std::size_t(v)];
    if (!t.fbo.isValid()) {
      GLuint id = 0;
      glGenFramebuffers(1, &id);
      t.fbo.reset(id);
      t.colour = makeTexture(GL_RGBA8, sizes[v].x, sizes[v].y, GL_RGBA, GL_UNSIGNED_BYTE, nullptr,
                             GL_CLAMP_TO_EDGE);
      glBindFramebuffer(GL_FRAMEBUFFER, t.fbo.get());
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.colour.get(),
                             0);
      t.size = sizes[v];
      glActiveTexture(GL_TEXTURE0);
      glBindTexture(GL_TEXTURE_2D, backgroundTex_.get());
    }
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo.get());
    glViewport(0, 0, t.size.x, t.size.y);
    glClearColor(0, 0, 0, 0);
    glClear(GL_COLOR_BUFFER_BIT);
    glUniform1i(loc(probeProgram_, "uMode"), v);
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, GLuint(target));
  glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
  checkGl("Renderer::drawProbeViews");
}

unsigned Renderer::probeTexture(ProbeView view) const {
  return probes_[std::size_t(view)].colour.get();
}
glm::ivec2 Renderer::probeSize(ProbeView view) const { return probes_[std::size_t(view)].size; }

void Renderer::finish() { glFinish(); }

std::vector<std::uint8_t> Renderer::readRgb8(glm::ivec2 size) {
  std::vector<std::uint8_t> px(std::size_t(size.x) * size.y * 3);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, size.x, size.y, GL_RGB, GL_UNSIGNED_BYTE, px.data());
  flipRows(px, std::size_t(size.x) * 3, size.y);
  return px;
}

}  // namespace lp::gl
