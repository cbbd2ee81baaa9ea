#include "liveprobe/sh/engines.h"

#include <array>

namespace lp {

namespace {

struct EngineInfo {
  Engine engine;
  std::string_view name;
  // Rows of engineFromWorld: engine axis i = dot(row i, world direction).
  glm::vec3 x, y, z;
};

// The frames of the table in engines.h, one row per engine axis.
constexpr std::array<EngineInfo, 6> kEngines{{
    {Engine::Three, "three", {-1, 0, 0}, {0, 0, 1}, {0, -1, 0}},
    {Engine::WebXr, "webxr", {-1, 0, 0}, {0, 0, 1}, {0, -1, 0}},
    {Engine::Babylon, "babylon", {0, -1, 0}, {0, 0, 1}, {-1, 0, 0}},
    {Engine::Filament, "filament", {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}},
    {Engine::Unity, "unity", {-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
    {Engine::Gltf, "gltf", {0, -1, 0}, {0, 0, 1}, {1, 0, 0}},
}};

const EngineInfo& info(Engine e) {
  for (const auto& i : kEngines)
    if (i.engine == e) return i;
  return kEngines[0];
}

/// The basis constant Y_k of liveprobe/sh/sh.h for coefficient k.
constexpr float basisConstant(int k) {
  constexpr std::array<float, kShCount> c{kY00, kY1, kY1, kY1, kY2, kY2, kY20, kY2, kY22};
  return c[std::size_t(k)];
}

}  // namespace

std::string_view engineName(Engine e) { return info(e).name; }

std::optional<Engine> parseEngine(std::string_view name) {
  for (const auto& i : kEngines)
    if (i.name == name) return i.engine;
  return std::nullopt;
}

glm::mat3 engineFromWorld(Engine e) {
  const EngineInfo& i = info(e);
  // glm is column-major: column j holds the engine coordinates of world axis j.
  return glm::transpose(glm::mat3(i.x, i.y, i.z));
}

Sh9 toEngineFrame(const Sh9& radiance, Engine e) { return rotateSh(radiance, engineFromWorld(e)); }

Sh9 preScaledIrradiance(const Sh9& radiance) {
  Sh9 s = radiance;
  for (int k = 0; k < kShCount; ++k)
    s.c[k] *= float(double(shCosineLobe(shBand(k))) / kPi) * basisConstant(k);
  return s;
}

Sh9 condonShortley(const Sh9& sh) {
  Sh9 s = sh;
  for (int k : {1, 3, 5, 7}) s.c[k] = -s.c[k];
  return s;
}

BabylonPolynomial babylonPolynomial(const Sh9& h) {
  // SphericalPolynomial.updateFromHarmonics, term for term (its rounded constants included, so
  // that an engine reading either form sees the same numbers).
  const float invPi = float(1.0 / kPi);
  BabylonPolynomial p;
  p.x = h.c[3] * -1.02333f * invPi;
  p.y = h.c[1] * -1.02333f * invPi;
  p.z = h.c[2] * 1.02333f * invPi;
  const Rgb a = h.c[6] * 0.247708f, b = h.c[8] * 0.429043f;
  p.xx = (h.c[0] * 0.886277f - a + b) * invPi;
  p.yy = (h.c[0] * 0.886277f - a - b) * invPi;
  p.zz = (h.c[0] * 0.886277f + h.c[6] * 0.495417f) * invPi;
  p.yz = h.c[5] * -0.858086f * invPi;
  p.zx = h.c[7] * -0.858086f * invPi;
  p.xy = h.c[4] * 0.858086f * invPi;
  return p;
}

}  // namespace lp
