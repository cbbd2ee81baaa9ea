#include "scene.h"

#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>

#include "liveprobe/frame/input_file.h"
#include "liveprobe/sh/error.h"

namespace lp::cli {

Mesh meshFrom(const SceneSettings& sc) {
  const std::string& model = sc.model;
  Mesh m;
  if (model == "sphere") {
    m = makeUvSphere();
  } else {
    try {
      requireRegularFile(model);
      m = loadMesh(model);
    } catch (const MeshError& e) {
      throw Error(e.what());
    }
  }
  glm::mat3 turn(1.0f);
  if (sc.upZ)
    turn =
        glm::mat3(glm::vec3(1, 0, 0), glm::vec3(0, 0, -1), glm::vec3(0, 1, 0));  // file z -> GL y
  // The bundled test models face the camera by default; spot.obj (Keenan Crane's cow) is stored
  // facing -z, away from the default camera on +z. --model-rotate replaces this default.
  const std::string file = std::filesystem::path(model).filename().string();
  const Triple v =
      sc.modelRotate ? *sc.modelRotate : Triple{file == "spot.obj" ? 180.0 : 0.0, 0, 0};
  // About the model's own up (GL y), right (x) and view (z) axes, applied yaw first.
  const glm::mat4 r = glm::rotate(glm::mat4(1.0f), glm::radians(float(v[2])), glm::vec3(0, 0, 1)) *
                      glm::rotate(glm::mat4(1.0f), glm::radians(float(v[1])), glm::vec3(1, 0, 0)) *
                      glm::rotate(glm::mat4(1.0f), glm::radians(float(v[0])), glm::vec3(0, 1, 0));
  turn = glm::mat3(r) * turn;
  for (auto& p : m.positions) p = turn * p;
  for (auto& n : m.normals) n = turn * n;
  fitToUnitSphere(m);
  return m;
}

gl::Camera cameraFrom(const SceneSettings& sc) {
  gl::Camera c;
  c.yawDeg = float(sc.yaw.value_or(c.yawDeg));
  c.pitchDeg = float(sc.pitch.value_or(c.pitchDeg));
  c.distance = float(sc.distance.value_or(c.distance));
  return c;
}

float autoExposure(const Sh9& withoutLights, bool environment, const std::vector<Light>& lights) {
  const Sh9 radiance = withoutLights + lightsToSh(lights);  // the whole environment's
  if (environment) {
    const float meanRadiance = luminance(radiance.c[0]) * kY00;
    return meanRadiance > 1e-12f ? 0.18f / meanRadiance : 1.0f;
  }
  // Luminance is linear, so Y(E(n)) is the irradiance of the luminance coefficients, and its
  // peak is minus the minimum of their negation: the core's minimum finder does the search.
  Sh9 negY;
  for (int k = 0; k < kShCount; ++k)
    negY.c[std::size_t(k)] = glm::vec3(-luminance(radiance.c[std::size_t(k)]));
  const float peak = -minIrradiance(negY).value.x;
  const float peakRadiance = peak / kA0;  // a white Lambertian surface shows E / pi
  return peakRadiance > 1e-12f ? 1.0f / peakRadiance : 1.0f;
}

gl::ShadingSettings shadingFrom(const SceneSettings& sc, const Sh9& radiance, bool environment,
                                const std::vector<Light>& lights) {
  gl::ShadingSettings s;
  s.exposure = sc.exposure ? float(*sc.exposure) : autoExposure(radiance, environment, lights);
  s.toneMap = sc.toneMap;
  s.background = !sc.noBackground;
  s.displayReferredBackground = !sc.tonemapBackground;
  s.shadows = sc.shadows;
  s.ground = sc.ground;
  s.samples = sc.msaa;
  return s;
}

}  // namespace lp::cli
