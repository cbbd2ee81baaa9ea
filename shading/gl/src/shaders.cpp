#include "shaders.h"

namespace lp::gl::shaders {

// Shared by every fragment shader: pi (GLSL's one statement of it), exposure, tone map, sRGB
// encoding.
#define LP_DISPLAY_GLSL                                                                            \
  "const float PI = 3.14159265358979;\n"                                                           \
  "uniform float uExposure;\n"                                                                     \
  "uniform int uToneMap; // 0 ACES (Narkowicz fit), 1 Reinhard, 2 linear clamp\n"                  \
  "vec3 toneMap(vec3 c) {\n"                                                                       \
  "  c = max(c * uExposure, vec3(0.0));\n"                                                         \
  "  if (uToneMap == 0) c = clamp((c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14), 0.0, " \
  "1.0);\n"                                                                                        \
  "  else if (uToneMap == 1) c = c / (1.0 + c);\n"                                                 \
  "  return clamp(c, 0.0, 1.0);\n"                                                                 \
  "}\n"                                                                                            \
  "vec3 srgbEncode(vec3 c) {\n"                                                                    \
  "  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));\n"  \
  "}\n"

// Shared by the model and the probe views: irradiance from the coefficients plus the lights.
// The lights' loop is compiled only where LP_LIGHTS is defined: on llvmpipe it costs the model
// pass 10-20% even with no light, so the renderer keeps a model variant without it.
// shIrradiance is R&H eq. 12, E(n) = n4^T M n4 with n in the R&H world frame, term for term the
// CPU lp::evalIrradianceQuadratic() (shading/sh/src/sh.cpp); lightIrradiance is a uniform disc's
// exact clamped cosine, term for term lp::lightIrradiance() (shading/sh/src/lights.cpp).
#define LP_IRRADIANCE_GLSL                                                             \
  "const int MAX_LIGHTS = 4;\n"                                                        \
  "uniform mat4 uShR, uShG, uShB;\n"                                                   \
  "uniform int uLightCount;\n"                                                         \
  "uniform vec3 uLightDir[MAX_LIGHTS];\n"                                              \
  "uniform vec3 uLightPower[MAX_LIGHTS];\n"                                            \
  "uniform float uLightRadius[MAX_LIGHTS];\n"                                          \
  "vec3 shIrradiance(vec3 n) {\n"                                                      \
  "  vec4 n4 = vec4(n, 1.0);\n"                                                        \
  "  return vec3(dot(n4, uShR * n4), dot(n4, uShG * n4), dot(n4, uShB * n4));\n"       \
  "}\n"                                                                                \
  "vec3 lightIrradiance(int i, vec3 n) {\n"                                            \
  "  float c = dot(n, uLightDir[i]);\n"                                                \
  "  float sa = sin(uLightRadius[i]), ca = cos(uLightRadius[i]);\n"                    \
  "  if (c >= sa) return uLightPower[i] * (c * (1.0 + ca) * 0.5);\n"                   \
  "  if (c <= -sa) return vec3(0.0);\n"                                                \
  "  float sHalf = sin(0.5 * uLightRadius[i]);\n"                                      \
  "  vec3 radiance = uLightPower[i] / (4.0 * PI * sHalf * sHalf);\n"                   \
  "  if (sa < 0.02) {\n"                                                               \
  "    float t0 = -c / sa, r = sqrt(max(0.0, 1.0 - t0 * t0));\n"                       \
  "    float f = c * (0.5 * PI - t0 * r - asin(t0)) + (2.0 / 3.0) * sa * r * r * r;\n" \
  "    return radiance * max(sa * sa * f, 0.0);\n"                                     \
  "  }\n"                                                                              \
  "  float s = sqrt(max(0.0, 1.0 - c * c));\n"                                         \
  "  float x = ca / sa, y = clamp(-x * c / s, -1.0, 1.0);\n"                           \
  "  float q = s * sqrt(1.0 - y * y);\n"                                               \
  "  float f = (c * acos(y) - x * q) * sa * sa + atan(q / x);\n"                       \
  "  return radiance * max(f, 0.0);\n"                                                 \
  "}\n"                                                                                \
  "vec3 irradiance(vec3 n) {\n"                                                        \
  "  vec3 E = shIrradiance(n);\n"                                                      \
  "#ifdef LP_LIGHTS\n"                                                                 \
  "  for (int i = 0; i < uLightCount; ++i) E += lightIrradiance(i, n);\n"              \
  "#endif\n"                                                                           \
  "  return E;\n"                                                                      \
  "}\n"

const char* const kModelVs = R"(#version 330 core
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec2 aUv;
uniform mat4 uViewProj;
out vec3 vNormal;
out vec2 vUv;
void main() {
  vNormal = aNormal;  // the model matrix is the identity: meshes are fitted on the CPU
  vUv = aUv;
  gl_Position = uViewProj * vec4(aPos, 1.0);
}
)";

const char* const kModelFs = "#version 330 core\n" LP_DISPLAY_GLSL LP_IRRADIANCE_GLSL R"(
in vec3 vNormal;
in vec2 vUv;
out vec4 fragColor;
uniform mat3 uWorldFromGl;  // liveprobe/sh/axes.h
uniform vec3 uAlbedo;
uniform bool uHasTexture;
uniform sampler2D uAlbedoTex;
uniform int uOutput;        // 0 display, 1 raw irradiance, 2 world normal

void main() {
  vec3 n = normalize(uWorldFromGl * normalize(vNormal));
  vec3 E = irradiance(n);
  if (uOutput != 0) {
    fragColor = vec4(uOutput == 1 ? E : n, 1.0);
    return;
  }
  vec3 albedo = uAlbedo;
  if (uHasTexture) albedo *= texture(uAlbedoTex, vUv).rgb;
  vec3 radiance = albedo * E / PI;  // Lambertian: B = rho E / pi
  fragColor = vec4(srgbEncode(toneMap(radiance)), 1.0);
}
)";

// A full-screen triangle from gl_VertexID; no vertex buffer.
const char* const kBackgroundVs = R"(#version 330 core
out vec2 vNdc;
void main() {
  vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2) * 2.0 - 1.0;
  vNdc = p;
  gl_Position = vec4(p, 1.0, 1.0);
}
)";

// The panorama seen in world direction w (R&H frame): the environment's orientation, the
// layout's mapping and the background look. Shared by the background and the probe views.
#define LP_PANORAMA_GLSL                                                                         \
  "uniform sampler2D uPanorama;\n"                                                               \
  "uniform int uMapping;          // 0 equirect, 1 angular (liveprobe/sh/layout.h)\n"            \
  "uniform mat3 uFileFromWorld;   // inverse of the environment's orientation\n"                 \
  "uniform float uPanoramaScale;  // the input exposure of an 8-bit frame, else 1\n"             \
  "uniform bool uDisplayReferred; // show the texels as the source looks: no exposure, no tone " \
  "map\n"                                                                                        \
  "uniform float uDisplayDivide;  // undoes the input exposure of a decoded 8-bit float "        \
  "panorama\n"                                                                                   \
  "vec2 panoramaUv(vec3 w) {\n"                                                                  \
  "  w = uFileFromWorld * w;\n"                                                                  \
  "  if (uMapping == 0) {\n"                                                                     \
  "    float t = acos(clamp(w.z, -1.0, 1.0));\n"                                                 \
  "    float p = atan(w.y, w.x);\n"                                                              \
  "    if (p < 0.0) p += 2.0 * PI;\n"                                                            \
  "    return vec2(p / (2.0 * PI), t / PI);\n"                                                   \
  "  }\n"                                                                                        \
  "  vec3 l = vec3(-w.y, w.z, -w.x);  // worldToAngular\n"                                       \
  "  float r = acos(clamp(l.z, -1.0, 1.0)) / PI;\n"                                              \
  "  float p = atan(l.y, l.x);\n"                                                                \
  "  return vec2(0.5 + 0.5 * r * cos(p), 0.5 - 0.5 * r * sin(p));\n"                             \
  "}\n"                                                                                          \
  "vec3 panoramaDisplay(vec3 w) {\n"                                                             \
  "  vec3 c = textureLod(uPanorama, panoramaUv(w), 0.0).rgb;\n"                                  \
  "  if (uDisplayReferred) return srgbEncode(clamp(c / uDisplayDivide, 0.0, 1.0));\n"            \
  "  return srgbEncode(toneMap(c * uPanoramaScale));\n"                                          \
  "}\n"

const char* const kBackgroundFs = "#version 330 core\n" LP_DISPLAY_GLSL LP_PANORAMA_GLSL R"(
in vec2 vNdc;
out vec4 fragColor;
uniform mat4 uInvViewProj;
uniform mat3 uWorldFromGl;

void main() {
  vec4 a = uInvViewProj * vec4(vNdc, -1.0, 1.0), b = uInvViewProj * vec4(vNdc, 1.0, 1.0);
  vec3 w = normalize(uWorldFromGl * (b.xyz / b.w - a.xyz / a.w));
  fragColor = vec4(panoramaDisplay(w), 1.0);
}
)";

// The probe views of the HUD, each drawn into a small texture by a full-screen triangle:
// 0: the whole panorama unwrapped as an equirect (the world's, after orientation);
// 1: a grey (50%) diffuse ball lit by the coefficients; 2: a chrome ball reflecting the
// environment. The balls are seen orthographically from the camera's direction.
const char* const kProbeFs =
    "#version 330 core\n#define LP_LIGHTS\n" LP_DISPLAY_GLSL LP_PANORAMA_GLSL LP_IRRADIANCE_GLSL R"(
in vec2 vNdc;
out vec4 fragColor;
uniform int uMode;
uniform mat3 uWorldFromView;   // camera space -> R&H world
uniform bool uHavePanorama;

void main() {
  if (uMode == 0) {
    float p = (vNdc.x * 0.5 + 0.5) * 2.0 * PI, t = (0.5 - 0.5 * vNdc.y) * PI;
    vec3 w = vec3(sin(t) * cos(p), sin(t) * sin(p), cos(t));
    fragColor = vec4(uHavePanorama ? panoramaDisplay(w) : vec3(0.0), 1.0);
    return;
  }
  float r2 = dot(vNdc, vNdc);
  if (r2 > 1.0) {
    fragColor = vec4(0.0);
    return;
  }
  vec3 nView = vec3(vNdc, sqrt(1.0 - r2));
  if (uMode == 1) {
    vec3 E = irradiance(normalize(uWorldFromView * nView));
    fragColor = vec4(srgbEncode(toneMap(0.5 * E / PI)), 1.0);
  } else {
    vec3 r = reflect(vec3(0.0, 0.0, -1.0), nView);
    fragColor = vec4(uHavePanorama ? panoramaDisplay(normalize(uWorldFromView * r)) : vec3(0.0), 1.0);
  }
}
)";

}  // namespace lp::gl::shaders
