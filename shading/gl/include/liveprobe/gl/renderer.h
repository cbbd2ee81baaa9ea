#pragma once
// Draws a model lit by nine SH coefficients, in one pass per pixel: E(n) = n4^T M n4 from three
// 4x4 uniforms, albedo (optionally textured) * E / pi, exposure, a tone map and sRGB output. The
// panorama is drawn behind it in the same orientation. Needs a current GL 3.3 core context;
// knows nothing of GLFW or OSMesa.
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "liveprobe/gl/gpu_image.h"
#include "liveprobe/gl/handles.h"
#include "liveprobe/gl/mesh.h"
#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/sh.h"

namespace lp::gl {

enum class ToneMap : std::uint8_t { Aces, Reinhard, Linear };
enum class OutputMode : std::uint8_t {
  Display,     ///< tone-mapped sRGB colour
  Irradiance,  ///< raw E(n) per channel (for float targets and tests)
  Normal,      ///< the unit normal in the R&H world frame (debug view, tests)
};
/// How the background texture maps to directions (liveprobe/sh/layout.h has the definitions).
enum class BackgroundMapping : std::uint8_t { Equirect, Angular };

/// An orbit camera around the origin (GL frame). yaw 0, pitch 0 looks from +Z towards -Z.
struct Camera {
  float yawDeg = 0.0f;
  float pitchDeg = 0.0f;
  float distance = 3.2f;
  float fovYDeg = 40.0f;
  /// The part of the frame the model is framed in (x0, y0, x1, y1 as fractions of the frame,
  /// y up): beside a HUD's panels, say. The projection is shifted and scaled so that the view
  /// the whole frame would show fits this part (by its height, or by its width where the part is
  /// narrower than square); the background still fills the frame, in the same projection.
  glm::vec4 frame{0.0f, 0.0f, 1.0f, 1.0f};

  glm::vec3 eye() const;
  glm::mat4 view() const;
  glm::mat4 projection(float aspect) const;
};

struct ShadingSettings {
  float exposure = 1.0f;
  ToneMap toneMap = ToneMap::Aces;
  bool background = true;
  OutputMode output = OutputMode::Display;
  /// Multisample anti-aliasing: 1 (off) or the samples per pixel of an offscreen target that is
  /// resolved into the bound framebuffer. Display output only. (The app's default is 4.)
  int samples = 1;
  /// An 8-bit (sRGB) background is shown as the source looks: no exposure, no tone map.
  bool displayReferredBackground = true;
  /// The first light casts the model's shadow through a shadow map (on the model and
  /// the ground), its soft edge sized by the light's angular radius.
  bool shadows = false;
  /// A shadow catcher plane under the model (the background, darkened by the model's
  /// shadow and ambient occlusion).
  bool ground = false;
  /// The 3D view drawn at this fraction of the frame's width and height (into an offscreen
  /// target, then scaled up with linear filtering): a window on a software rasterizer keeps its
  /// frame rate this way (dynamic resolution). 1 draws at full size.
  float renderScale = 1.0f;
};

/// The small views the HUD shows (Renderer::drawProbeViews).
enum class ProbeView : std::uint8_t { Panorama, DiffuseBall, ChromeBall };

/// A float RGBA offscreen target with depth, for exact readback.
class FloatTarget {
 public:
  FloatTarget(int width, int height);
  void bind() const;
  /// RGBA floats, rows top to bottom.
  std::vector<float> readRgba() const;
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int width_, height_;
  Framebuffer fbo_;
  Texture colour_;
  Renderbuffer depth_;
};

class Renderer {
 public:
  /// Compiles the programs. Throws ContextError (liveprobe/gl/context.h) on a GL failure.
  Renderer();

  void setMesh(const Mesh& mesh);
  /// Linear RGB albedo texture (rows top to bottom); multiplies Mesh::albedo.
  void setAlbedoTexture(const float* rgb, int width, int height);
  void setLighting(const Sh9& radiance);
  /// The coefficients and disc lights (liveprobe/sh/lights.h) together: the shaders add each
  /// light's exact clamped cosine to the coefficients' irradiance. Every light is drawn: more
  /// than lp::kMaxLights is a programming error (std::invalid_argument).
  void setLighting(const Sh9& residual, const std::vector<Light>& lights);
  /// Linear RGB panorama for the background (rows top to bottom). `displayScale` > 0 says it was
  /// decoded from an 8-bit (sRGB) source and multiplied by that scale: shown display-referred
  /// (ShadingSettings::displayReferredBackground), it is divided by it and encoded back, so it
  /// looks as the source does. 0: a scene-referred (HDR) panorama, exposed and tone-mapped.
  void setBackground(const float* rgb, int width, int height, BackgroundMapping mapping,
                     float displayScale = 0.0f);

  /// A linear RGB panorama kept on the GPU by a context sharing this one's objects (a bracket
  /// merged there), copied into the background's texture on the GPU, its values times `scale`
  /// (the exposure). Where its maker is gone, the background stays as it was.
  void setBackground(const GpuImage& image, BackgroundMapping mapping, float scale);

  /// 8-bit sRGB BGR panorama (rows top to bottom): the texture unit decodes sRGB to linear, and
  /// the shader multiplies by `scale` (the input exposure). Saves a per-frame CPU conversion.
  void setBackgroundSrgb8(const std::uint8_t* bgr, int width, int height, BackgroundMapping mapping,
                          float scale);

  /// Orientation of the environment: a light at file direction d lies in world direction O d.
  /// O is orthogonal (a rotation, or a rotation times a reflection for a flipped panorama). The
  /// background and the probe views look up the panorama through its inverse; the lighting
  /// passed to setLighting() must already be turned by the same O (lp::rotateSh).
  void setEnvOrientation(const glm::mat3& worldFromFile);

  /// Draws into the currently bound framebuffer (viewport `size`).
  void draw(glm::ivec2 size, const Camera& camera, const ShadingSettings& settings);

  /// Renders the probe views (the panorama unwrapped, a grey diffuse ball, a chrome ball) into
  /// small textures for the HUD, seen from `camera`'s direction. Restores the bound framebuffer.
  void drawProbeViews(const Camera& camera, const ShadingSettings& settings);
  /// The GL texture name of a probe view (0 before the first drawProbeViews), and its size.
  unsigned probeTexture(ProbeView view) const;
  glm::ivec2 probeSize(ProbeView view) const;

  /// Waits until GL has finished all commands (for frame timing).
  static void finish();

  /// Reads the bound framebuffer as 8-bit RGB, rows top to bottom.
  static std::vector<std::uint8_t> readRgb8(glm::ivec2 size);

 private:
  struct Target {  ///< an offscreen colour (+ depth) target
    Framebuffer fbo;
    Texture colour;
    Renderbuffer colourMs, depth;
    glm::ivec2 size{0};
    int samples = 0;
  };
  void ensureMultisample(glm::ivec2 size, int samples);
  void ensureScaled(glm::ivec2 size);
  /// The 3D view at `size` into the bound framebuffer.
  void drawView(glm::ivec2 size, const Camera& camera, const ShadingSettings& s);
  /// The first light's depth map of the mesh; sets the shadow uniforms' values.
  void renderShadowMap();
  void setShadowUniforms(const Program& program, bool on) const;
  void drawGround(const glm::mat4& viewProj, const Camera& camera, const ShadingSettings& s);
  void bindPanorama(const Program& program, const ShadingSettings& s) const;
  /// The background's float texture of `width` x `height`, bound: the last one where it fits.
  void bindFloatBackground(int width, int height, BackgroundMapping mapping);

  // Variants: without lights, with lights, with lights and the shadow map (see shaders.cpp).
  Program modelProgram_, modelLitProgram_, modelShadowProgram_, backgroundProgram_, probeProgram_,
      depthProgram_, groundProgram_, groundShadowProgram_;
  // The shadow map (`shadows`) and the ground (`ground`).
  static constexpr int kShadowSize = 2048;
  Framebuffer shadowFbo_;
  Texture shadowDepth_;
  glm::mat4 lightViewProj_{1.0f};
  float shadowTexelWorld_ = 0.0f, shadowDepthRange_ = 1.0f;
  glm::vec4 bounds_{0.0f, 0.0f, 0.0f, 1.0f};  ///< the mesh's bounding sphere (GL frame)
  float groundY_ = -1.0f;                     ///< the mesh's lowest point
  VertexArray groundVao_;
  Buffer groundVertices_;
  Target msaa_, scaled_;
  std::array<Target, 3> probes_;
  glm::mat3 fileFromWorld_{1.0f};
  VertexArray meshVao_, emptyVao_;
  Buffer positions_, normals_, uvs_, indices_;
  GLsizei indexCount_ = 0;
  bool hasUv_ = false;
  glm::vec3 albedo_{0.8f};
  Texture albedoTex_, backgroundTex_;
  BackgroundMapping backgroundMapping_ = BackgroundMapping::Equirect;
  float backgroundScale_ = 1.0f, backgroundDisplayScale_ = 0.0f;
  int backgroundW_ = 0, backgroundH_ = 0;
  bool backgroundSrgb_ = false;
  std::array<glm::mat4, 3> sh_{};
  std::vector<Light> lights_;
  void setIrradianceUniforms(const Program& program) const;
};

/// Throws ContextError if glGetError() reports an error, naming `where`.
void checkGl(const char* where);

}  // namespace lp::gl
