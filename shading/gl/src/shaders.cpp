#include "shaders.h"

#include "liveprobe/sh/lights.h"

static_assert(lp::kMaxLights == 8, "MAX_LIGHTS in LP_IRRADIANCE_GLSL is lp::kMaxLights");

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
// clang-format off
#define LP_IRRADIANCE_GLSL                                                                             \
  "const int MAX_LIGHTS = 8;\n"                                                                        \
  "uniform mat4 uShR, uShG, uShB;\n"                                                                   \
  "uniform int uLightCount;\n"                                                                         \
  "uniform vec3 uLightDir[MAX_LIGHTS];\n"                                                              \
  "uniform vec3 uLightPower[MAX_LIGHTS];\n"                                                            \
  "uniform vec3 uLightTrig[MAX_LIGHTS];  // sin a, cos a, sin(a / 2) of each angular radius a\n"       \
  "vec3 shIrradiance(vec3 n) {\n"                                                                      \
  "  vec4 n4 = vec4(n, 1.0);\n"                                                                        \
  "  return vec3(dot(n4, uShR * n4), dot(n4, uShG * n4), dot(n4, uShB * n4));\n"                       \
  "}\n"                                                                                                \
  "vec3 lightIrradiance(int i, vec3 n) {\n"                                                            \
  "  float c = dot(n, uLightDir[i]);\n"                                                                \
  "  float sa = uLightTrig[i].x, ca = uLightTrig[i].y;\n"                                              \
  "  if (c >= sa) return uLightPower[i] * (c * (1.0 + ca) * 0.5);\n"                                   \
  "  if (c <= -sa) return vec3(0.0);\n"                                                                \
  "  float sHalf = uLightTrig[i].z;\n"                                                                 \
  "  vec3 radiance = uLightPower[i] / (4.0 * PI * sHalf * sHalf);\n"                                   \
  "  if (sa < 0.02) {\n"                                                                               \
  "    float t0 = -c / sa, r = sqrt(max(0.0, 1.0 - t0 * t0));\n"                                       \
  "    float f = c * (0.5 * PI - t0 * r - asin(t0)) + (2.0 / 3.0) * sa * r * r * r;\n"                 \
  "    return radiance * max(sa * sa * f, 0.0);\n"                                                     \
  "  }\n"                                                                                              \
  "  float s = sqrt(max(0.0, 1.0 - c * c));\n"                                                         \
  "  float x = ca / sa, y = clamp(-x * c / s, -1.0, 1.0);\n"                                           \
  "  float q = s * sqrt(1.0 - y * y);\n"                                                               \
  "  float f = (c * acos(y) - x * q) * sa * sa + atan(q / x);\n"                                       \
  "  return radiance * max(f, 0.0);\n"                                                                 \
  "}\n"                                                                                                \
  "vec3 irradiance(vec3 n) {\n"                                                                        \
  "  vec3 E = shIrradiance(n);\n"                                                                      \
  "#ifdef LP_LIGHTS\n"                                                                                 \
  "  for (int i = 0; i < uLightCount; ++i) E += lightIrradiance(i, n);\n"                              \
  "#endif\n"                                                                                           \
  "  return E;\n"                                                                                      \
  "}\n"                                                                                                \
  "#ifdef LP_LIGHTS\n"                                                                                 \
  "vec3 irradianceSeen(vec3 n, float sunVisible) {\n"                                                  \
  "  vec3 E = shIrradiance(n);\n"                                                                      \
  "  for (int i = 0; i < uLightCount; ++i)\n"                                                          \
  "    E += (i == 0 ? sunVisible : 1.0) * lightIrradiance(i, n);\n"                                    \
  "  return E;\n"                                                                                      \
  "}\n"                                                                                                \
  "#endif\n"
// clang-format on

// The first light's visibility through the shadow map (--shadows; compiled where LP_SHADOWS is
// defined, since llvmpipe runs a skipped branch's texture taps anyway): PCSS-style, so a small sun
// gives a sharp shadow and a large one a soft shadow. A blocker search (16 taps of a Vogel disc
// over 24 texels) finds the mean occluder depth; the penumbra on the receiver is
// (receiver - blocker) * tan(angular radius), and 16 PCF taps of a Vogel disc span it (at least
// one texel), turned per pixel (interleaved gradient noise) so a wide penumbra is smooth noise
// rather than bands. Positions are in the GL world frame.
#define LP_SHADOW_GLSL                                                                         \
  "uniform bool uShadows;\n"                                                                   \
  "uniform sampler2D uShadowMap;\n"                                                            \
  "uniform mat4 uLightViewProj;\n"                                                             \
  "uniform float uShadowTexel;      // 1 / shadow map size\n"                                  \
  "uniform float uShadowTexelWorld; // one texel, in world units\n"                            \
  "uniform float uShadowDepthRange; // world units per unit of stored depth\n"                 \
  "uniform float uTanRadius;        // tan of the light's angular radius\n"                    \
  "vec2 vogel(int i, float turn) {\n"                                                          \
  "  float r = sqrt((float(i) + 0.5) / 16.0), a = float(i) * 2.39996323 + turn;\n"             \
  "  return r * vec2(cos(a), sin(a));\n"                                                       \
  "}\n"                                                                                        \
  "float sunVisibility(vec3 p, vec3 n) {\n"                                                    \
  "  if (!uShadows) return 1.0;\n"                                                             \
  "  vec4 q = uLightViewProj * vec4(p + n * 3.0 * uShadowTexelWorld, 1.0);\n"                  \
  "  vec3 c = q.xyz / q.w * 0.5 + 0.5;\n"                                                      \
  "  if (any(lessThan(c, vec3(0.0))) || any(greaterThan(c, vec3(1.0)))) return 1.0;\n"         \
  "  float receiver = c.z - 2.0 * uShadowTexelWorld / uShadowDepthRange;\n"                    \
  "  float turn = 6.2831853 * fract(52.9829189 * fract(dot(gl_FragCoord.xy, "                  \
  "vec2(0.06711056, 0.00583715))));\n"                                                         \
  "  float sum = 0.0, count = 0.0;\n"                                                          \
  "  for (int i = 0; i < 16; ++i) {\n"                                                         \
  "    float d = texture(uShadowMap, c.xy + vogel(i, turn) * 24.0 * uShadowTexel).r;\n"        \
  "    if (d < receiver) { sum += d; count += 1.0; }\n"                                        \
  "  }\n"                                                                                      \
  "  if (count == 0.0) return 1.0;\n"                                                          \
  "  float penumbra = (receiver - sum / count) * uShadowDepthRange * uTanRadius;\n"            \
  "  float radius = max(penumbra / uShadowTexelWorld, 1.0) * uShadowTexel;\n"                  \
  "  float lit = 0.0;\n"                                                                       \
  "  for (int i = 0; i < 16; ++i)\n"                                                           \
  "    lit += texture(uShadowMap, c.xy + vogel(i, turn) * radius).r < receiver ? 0.0 : 1.0;\n" \
  "  return lit / 16.0;\n"                                                                     \
  "}\n"

// The shadow map's depth pass: positions only.
const char* const kDepthVs = R"(#version 330 core
layout(location = 0) in vec3 aPos;
uniform mat4 uLightViewProj;
void main() { gl_Position = uLightViewProj * vec4(aPos, 1.0); }
)";
const char* const kDepthFs = R"(#version 330 core
void main() {}
)";

const char* const kModelVs = R"(#version 330 core
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec2 aUv;
uniform mat4 uViewProj;
out vec3 vNormal;
out vec2 vUv;
out vec3 vPos;
void main() {
  vNormal = aNormal;  // the model matrix is the identity: meshes are fitted on the CPU
  vUv = aUv;
  vPos = aPos;
  gl_Position = uViewProj * vec4(aPos, 1.0);
}
)";

const char* const kModelFs =
    "#version 330 core\n" LP_DISPLAY_GLSL LP_IRRADIANCE_GLSL LP_SHADOW_GLSL R"(
in vec3 vNormal;
in vec2 vUv;
in vec3 vPos;
out vec4 fragColor;
uniform mat3 uWorldFromGl;  // liveprobe/sh/axes.h
uniform vec3 uAlbedo;
uniform bool uHasTexture;
uniform sampler2D uAlbedoTex;
uniform int uOutput;        // 0 display, 1 raw irradiance, 2 world normal

void main() {
  vec3 n = normalize(uWorldFromGl * normalize(vNormal));
#if defined(LP_SHADOWS)
  // Only where the sun can reach: llvmpipe skips the shadow map's taps for whole blocks facing
  // away from it.
  float sun = dot(n, uLightDir[0]) > -uLightTrig[0].x
                  ? sunVisibility(vPos, normalize(vNormal)) : 1.0;
  vec3 E = irradianceSeen(n, sun);
#elif defined(LP_LIGHTS)
  vec3 E = irradiance(n);
#else
  vec3 E = irradiance(n);
#endif
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

// --ground: a shadow catcher under the model, as AR compositing does. It shows the background
// in the view ray's direction (the real floor is in the panorama), darkened by the luminance
// ratio of the irradiance it receives with the model there to without: the first light times
// its shadow-map visibility, and the coefficients' sky times 1 - F, F the form factor of the
// model's bounding sphere (R/d)^2 cos t, its ambient occlusion. Without a panorama it is a grey
// diffuse floor lit the same way.
const char* const kGroundVs = R"(#version 330 core
layout(location = 0) in vec3 aPos;
uniform mat4 uViewProj;
out vec3 vPos;
void main() {
  vPos = aPos;
  gl_Position = uViewProj * vec4(aPos, 1.0);
}
)";
const char* const kGroundFs =
    "#version 330 core\n#define LP_LIGHTS\n" LP_DISPLAY_GLSL LP_PANORAMA_GLSL LP_IRRADIANCE_GLSL
        LP_SHADOW_GLSL R"(
in vec3 vPos;
out vec4 fragColor;
uniform vec3 uEye;          // the camera, GL frame
uniform mat3 uWorldFromGl;
uniform vec4 uOccluder;     // the model's bounding sphere: centre (GL), radius
uniform bool uHavePanorama;
const vec3 Y = vec3(0.2126, 0.7152, 0.0722);

vec3 srgbDecode(vec3 c) {
  return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), c));
}

void main() {
  vec3 up = vec3(0.0, 0.0, 1.0);  // the floor's normal, R&H world frame
  vec3 sky = shIrradiance(up), lights = vec3(0.0);
  for (int i = 0; i < uLightCount; ++i) lights += lightIrradiance(i, up);
  vec3 sun = uLightCount > 0 ? lightIrradiance(0, up) : vec3(0.0);
#ifdef LP_SHADOWS
  float visible = sunVisibility(vPos, vec3(0.0, 1.0, 0.0));
#else
  float visible = 1.0;
#endif
  vec3 toC = uOccluder.xyz - vPos;
  float d = length(toC);
  float F = clamp(uOccluder.w * uOccluder.w / (d * d), 0.0, 1.0) * max(toC.y / d, 0.0);
  vec3 full = sky + lights, seen = sky * (1.0 - F) + lights - sun * (1.0 - visible);
  float k = clamp(dot(seen, Y) / max(dot(full, Y), 1e-30), 0.0, 1.0);
  if (uHavePanorama) {
    vec3 w = normalize(uWorldFromGl * (vPos - uEye));
    fragColor = vec4(srgbEncode(srgbDecode(panoramaDisplay(w)) * k), 1.0);
  } else {
    fragColor = vec4(srgbEncode(toneMap(0.5 * seen / PI)), 1.0);
  }
}
)";

}  // namespace lp::gl::shaders
