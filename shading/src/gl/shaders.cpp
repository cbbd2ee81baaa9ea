#include "shaders.h"

namespace lp::gl::shaders {

// Shared by both fragment shaders: exposure, tone map, sRGB encoding.
#define LP_DISPLAY_GLSL                                                                  \
  "uniform float uExposure;\n"                                                           \
  "uniform int uToneMap; // 0 ACES (Narkowicz fit), 1 Reinhard, 2 linear clamp\n"        \
  "vec3 toneMap(vec3 c) {\n"                                                             \
  "  c = max(c * uExposure, vec3(0.0));\n"                                               \
  "  if (uToneMap == 0) c = clamp((c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14), 0.0, 1.0);\n" \
  "  else if (uToneMap == 1) c = c / (1.0 + c);\n"                                       \
  "  return clamp(c, 0.0, 1.0);\n"                                                       \
  "}\n"                                                                                  \
  "vec3 srgbEncode(vec3 c) {\n"                                                          \
  "  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));\n" \
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

const char* const kModelFs = "#version 330 core\n" LP_DISPLAY_GLSL R"(
in vec3 vNormal;
in vec2 vUv;
out vec4 fragColor;
uniform mat4 uShR, uShG, uShB;
uniform mat3 uWorldFromGl;  // shading/axes.h
uniform vec3 uAlbedo;
uniform bool uHasTexture;
uniform sampler2D uAlbedoTex;
uniform int uOutput;        // 0 display, 1 raw irradiance, 2 world normal

// Irradiance (Ramamoorthi & Hanrahan 2001, eq. 12): E(n) = n4^T M n4, n4 = (n, 1), n in the
// R&H world frame. Term for term the CPU lp::evalIrradianceQuadratic() in shading/src/sh.cpp.
vec3 shIrradiance(vec3 n) {
  vec4 n4 = vec4(n, 1.0);
  return vec3(dot(n4, uShR * n4), dot(n4, uShG * n4), dot(n4, uShB * n4));
}

void main() {
  vec3 n = normalize(uWorldFromGl * normalize(vNormal));
  vec3 E = shIrradiance(n);
  if (uOutput != 0) {
    fragColor = vec4(uOutput == 1 ? E : n, 1.0);
    return;
  }
  vec3 albedo = uAlbedo;
  if (uHasTexture) albedo *= texture(uAlbedoTex, vUv).rgb;
  vec3 radiance = albedo * E / 3.14159265;  // Lambertian: B = rho E / pi
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

const char* const kBackgroundFs = "#version 330 core\n" LP_DISPLAY_GLSL R"(
in vec2 vNdc;
out vec4 fragColor;
uniform mat4 uInvViewProj;
uniform mat3 uWorldFromGl;
uniform sampler2D uPanorama;
uniform int uMapping;  // 0 equirect, 1 angular (capture/layout.h)
const float PI = 3.14159265358979;

void main() {
  vec4 a = uInvViewProj * vec4(vNdc, -1.0, 1.0), b = uInvViewProj * vec4(vNdc, 1.0, 1.0);
  vec3 w = normalize(uWorldFromGl * (b.xyz / b.w - a.xyz / a.w));
  vec2 uv;
  if (uMapping == 0) {
    float t = acos(clamp(w.z, -1.0, 1.0));
    float p = atan(w.y, w.x);
    if (p < 0.0) p += 2.0 * PI;
    uv = vec2(p / (2.0 * PI), t / PI);
  } else {
    vec3 l = vec3(-w.y, w.z, -w.x);  // worldToAngular
    float r = acos(clamp(l.z, -1.0, 1.0)) / PI;
    float p = atan(l.y, l.x);
    uv = vec2(0.5 + 0.5 * r * cos(p), 0.5 - 0.5 * r * sin(p));
  }
  fragColor = vec4(srgbEncode(toneMap(textureLod(uPanorama, uv, 0.0).rgb)), 1.0);
}
)";

}  // namespace lp::gl::shaders
