// The engine conventions of liveprobe/sh/engines.h, against independent truths: each frame is
// orthogonal with the handedness of its engine; a point light's radiance coefficients in an
// engine's frame equal the projection of the same light placed at the turned direction; the
// pre-scaled form evaluated as Filament and Unity evaluate it is E / pi from the basis sum; and
// the glTF frame is the GL frame of liveprobe/sh/axes.h. (The engines' own code checks the rest:
// tests/engines.)
#include <gtest/gtest.h>

#include <random>

#include "liveprobe/sh/axes.h"
#include "liveprobe/sh/engines.h"

namespace lp {
namespace {

constexpr Engine kAll[] = {Engine::Three,    Engine::WebXr, Engine::Babylon,
                           Engine::Filament, Engine::Unity, Engine::Gltf};

/// Radiance coefficients of a unit "point light" of solid angle 1 in direction d: L_k = Y_k(d).
Sh9 pointLight(glm::vec3 d) {
  Sh9 s;
  const auto y = shBasis(d);
  for (int k = 0; k < kShCount; ++k) s.c[k] = Rgb(y[k]);
  return s;
}

TEST(Engines, FramesAreOrthogonalWithTheirEnginesHandedness) {
  for (Engine e : kAll) {
    const glm::mat3 m = engineFromWorld(e);
    const glm::mat3 p = glm::transpose(m) * m;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(p[i][j], i == j ? 1.0f : 0.0f, 1e-6f);
    // Babylon and Unity are left-handed: the same picture is a rotation of liveprobe's
    // (right-handed) frame for them, a reflection for the right-handed engines, since
    // liveprobe's equirect convention describes the scene mirrored (liveprobe/sh/axes.h).
    const bool leftHanded = e == Engine::Babylon || e == Engine::Unity;
    EXPECT_NEAR(glm::determinant(m), leftHanded ? 1.0f : -1.0f, 1e-6f) << engineName(e);
    EXPECT_EQ(parseEngine(engineName(e)), e);
  }
  EXPECT_FALSE(parseEngine("povray"));
}

TEST(Engines, EveryFrameShowsUpAsUp) {
  for (Engine e : kAll) {
    const glm::vec3 up = engineFromWorld(e) * glm::vec3(0, 0, 1);
    EXPECT_EQ(up, glm::vec3(0, 1, 0)) << engineName(e);  // all of them are y-up
  }
}

TEST(Engines, GltfIsLiveprobesGlFrame) {
  std::mt19937 rng(3);
  std::normal_distribution<float> n;
  for (int i = 0; i < 20; ++i) {
    const glm::vec3 d = glm::normalize(glm::vec3(n(rng), n(rng), n(rng)));
    const glm::vec3 a = engineFromWorld(Engine::Gltf) * d, b = axes::glFromWorld(d);
    EXPECT_NEAR(glm::length(a - b), 0.0f, 1e-6f);
  }
}

TEST(Engines, CoefficientsTurnWithTheLight) {
  std::mt19937 rng(5);
  std::normal_distribution<float> n;
  for (Engine e : kAll)
    for (int i = 0; i < 10; ++i) {
      const glm::vec3 d = glm::normalize(glm::vec3(n(rng), n(rng), n(rng)));
      const Sh9 turned = toEngineFrame(pointLight(d), e);
      const Sh9 truth = pointLight(engineFromWorld(e) * d);
      for (int k = 0; k < kShCount; ++k) EXPECT_NEAR(turned.c[k].x, truth.c[k].x, 2e-5f);
    }
}

TEST(Engines, PreScaledPolynomialIsIrradianceOverPi) {
  std::mt19937 rng(7);
  std::normal_distribution<float> n;
  Sh9 L;
  for (auto& c : L.c) c = Rgb(n(rng), n(rng), n(rng));
  const Sh9 s = preScaledIrradiance(L);
  for (int i = 0; i < 50; ++i) {
    const glm::vec3 d = glm::normalize(glm::vec3(n(rng), n(rng), n(rng)));
    const float x = d.x, y = d.y, z = d.z;
    // Filament's Irradiance_SphericalHarmonics / Unity's ShadeSH9 polynomial.
    const Rgb p = s.c[0] + s.c[1] * y + s.c[2] * z + s.c[3] * x + s.c[4] * (y * x) +
                  s.c[5] * (y * z) + s.c[6] * (3 * z * z - 1) + s.c[7] * (z * x) +
                  s.c[8] * (x * x - y * y);
    const Rgb e = evalIrradiance(L, d) / float(kPi);
    EXPECT_NEAR(glm::length(p - e), 0.0f, 1e-5f * (1 + glm::length(e)));
  }
}

TEST(Engines, CondonShortleyNegatesTheOddOrdersOnly) {
  Sh9 L;
  for (int k = 0; k < kShCount; ++k) L.c[k] = Rgb(float(k + 1));
  const Sh9 c = condonShortley(L);
  for (int k = 0; k < kShCount; ++k)
    EXPECT_EQ(c.c[k].x, (k == 1 || k == 3 || k == 5 || k == 7) ? -float(k + 1) : float(k + 1));
  EXPECT_EQ(condonShortley(c), L);
}

}  // namespace
}  // namespace lp
