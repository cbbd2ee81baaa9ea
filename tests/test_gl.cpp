// Tier 3: the GL renderer for real on Mesa llvmpipe through OSMesa (headless).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <numbers>
#include <random>

#include "liveprobe/capture/image.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/gl/gl.h"
#include "liveprobe/gl/mesh.h"
#include "liveprobe/gl/renderer.h"
#include "liveprobe/sh/axes.h"
#include "liveprobe/sh/projector.h"
#include "test_util.h"

namespace {

using lp::Sh9;
using lp::gl::OutputMode;
constexpr int kSize = 256;

// One headless context for the whole suite.
class GlTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ctx_ = lp::gl::createGlContext({lp::gl::Backend::Headless, kSize, kSize, "test", false});
  }
  static void TearDownTestSuite() { ctx_.reset(); }

  // Renders one pass into a float target; RGBA rows top to bottom.
  static std::vector<float> pass(lp::gl::Renderer& r, const lp::gl::Camera& cam, OutputMode mode,
                                 float exposure = 1.0f, bool background = false) {
    lp::gl::FloatTarget target(kSize, kSize);
    target.bind();
    lp::gl::ShadingSettings s;
    s.output = mode;
    s.exposure = exposure;
    s.toneMap = lp::gl::ToneMap::Linear;
    s.background = background;
    r.draw({kSize, kSize}, cam, s);
    return target.readRgba();
  }

  static inline std::unique_ptr<lp::gl::GlContext> ctx_;
};

// The world-frame direction of the ray through pixel (x, y) (y from the top).
glm::vec3 pixelRayGl(const lp::gl::Camera& cam, int x, int y, glm::vec3* origin) {
  const glm::mat4 inv = glm::inverse(cam.projection(1.0f) * cam.view());
  const glm::vec2 ndc((x + 0.5f) / kSize * 2 - 1, 1 - (y + 0.5f) / kSize * 2);
  const glm::vec4 a = inv * glm::vec4(ndc, -1, 1), b = inv * glm::vec4(ndc, 1, 1);
  *origin = glm::vec3(a) / a.w;
  return glm::normalize(glm::vec3(b) / b.w - *origin);
}

// Analytic unit-sphere normal (GL frame) at pixel (x, y); false if the ray misses or grazes.
bool sphereNormal(const lp::gl::Camera& cam, int x, int y, glm::vec3* n, float minCos = 0.3f) {
  glm::vec3 o;
  const glm::vec3 d = pixelRayGl(cam, x, y, &o);
  const float b = glm::dot(o, d), c = glm::dot(o, o) - 1.0f, disc = b * b - c;
  if (disc < 0) return false;
  *n = glm::normalize(o + (-b - std::sqrt(disc)) * d);
  return glm::dot(*n, -d) > minCos;
}

std::string outputPath(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(LIVEPROBE_TEST_OUTPUT);
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

void saveDisplay(const std::vector<float>& rgba, const std::string& name) {
  std::vector<std::uint8_t> rgb(std::size_t(kSize) * kSize * 3);
  for (std::size_t i = 0; i < rgb.size() / 3; ++i)
    for (int c = 0; c < 3; ++c)
      rgb[3 * i + c] = std::uint8_t(std::lround(255 * std::clamp(rgba[4 * i + c], 0.0f, 1.0f)));
  lp::saveRgb8(outputPath(name), kSize, kSize, rgb.data());
}

// The largest relative difference, over the pixels that see the unit sphere (at least 5000 of
// them), between a float pass and `cpu` at the pixel's analytic normal (R&H world frame).
template <class Cpu>
double worstAgainstCpu(const lp::gl::Camera& cam, const std::vector<float>& px, Cpu cpu) {
  int covered = 0;
  double worst = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      glm::vec3 n;
      if (!sphereNormal(cam, x, y, &n)) continue;
      ++covered;
      const glm::vec3 e = cpu(lp::axes::worldFromGl(n));
      for (int c = 0; c < 3; ++c)
        worst =
            std::max(worst, double(std::abs(px[4 * (y * kSize + x) + c] - e[c]) / std::abs(e[c])));
    }
  EXPECT_GT(covered, 5000);
  return worst;
}

// GL against CPU: at every covered pixel of a unit sphere, E from the float framebuffer equals
// the CPU evaluation at the analytic normal of that pixel, within 1e-3 relative.
// A GL failure is liveprobe's one error type (lp::Error): wherever it happens, a command says it
// in one line and exits 1, never as an internal error. A background wider than the driver's
// largest texture makes GL_INVALID_VALUE.
TEST_F(GlTest, AGlFailureIsLiveprobesError) {
  int most = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &most);
  ASSERT_GT(most, 0);
  lp::gl::Renderer r;
  std::vector<std::uint8_t> bgr(std::size_t(most + 1) * 2 * 3, 128);
  try {
    r.setBackgroundSrgb8(bgr.data(), most + 1, 2, lp::gl::BackgroundMapping::Equirect, 1.0f);
    ADD_FAILURE() << "a " << most + 1 << "-pixel-wide texture was taken";
  } catch (const lp::Error& e) {
    EXPECT_NE(std::string(e.what()).find(": GL error 0x0501"), std::string::npos) << e.what();
  }
}

TEST_F(GlTest, IrradianceMatchesCpuPerPixel) {
  lp::gl::Renderer r;
  r.setMesh(lp::makeUvSphere(512, 256));
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-0.25f, 0.25f);
  for (int trial = 0; trial < 3; ++trial) {
    Sh9 L;
    L.c[0] = glm::vec3(1.0f, 0.8f, 1.2f);
    for (int k = 1; k < 9; ++k) L.c[k] = {u(rng), u(rng), u(rng)};
    r.setLighting(L);
    lp::gl::Camera cam;
    cam.yawDeg = 40.0f * trial;
    cam.pitchDeg = -20.0f + 20.0f * trial;
    const auto px = pass(r, cam, OutputMode::Irradiance);
    const double worst =
        worstAgainstCpu(cam, px, [&](glm::vec3 n) { return lp::evalIrradiance(L, n); });
    EXPECT_LT(worst, 1e-3) << "trial " << trial;
  }
}

// The same with disc lights beside the coefficients: the GLSL's lightIrradiance equals
// the CPU's at every pixel, a sharp sun and a wide disc whose horizon band crosses the sphere.
TEST_F(GlTest, IrradianceWithLightsMatchesCpuPerPixel) {
  lp::gl::Renderer r;
  r.setMesh(lp::makeUvSphere(512, 256));
  Sh9 L;
  L.c[0] = glm::vec3(1.0f, 0.8f, 1.2f);
  L.c[2] = glm::vec3(0.2f);
  std::vector<lp::Light> lights(2);
  lights[0].dir = glm::normalize(glm::vec3(-0.6f, -0.7f, 0.3f));
  lights[0].angularRadius = glm::radians(0.27f);
  lights[0].power = {6.0f, 5.5f, 5.0f};
  lights[1].dir = glm::normalize(glm::vec3(0.3f, -0.9f, -0.2f));
  lights[1].angularRadius = glm::radians(12.0f);
  lights[1].power = {0.5f, 1.0f, 2.0f};
  r.setLighting(L, lights);
  for (int trial = 0; trial < 2; ++trial) {
    lp::gl::Camera cam;
    cam.yawDeg = 70.0f + 60.0f * trial;
    const auto px = pass(r, cam, OutputMode::Irradiance);
    const double worst =
        worstAgainstCpu(cam, px, [&](glm::vec3 n) { return lp::evalIrradiance(L, lights, n); });
    EXPECT_LT(worst, 2e-3) << "trial " << trial;
  }
}

// Every light is drawn, up to lp::kMaxLights: eight lamps around the sphere (each seen by some of
// its pixels) against the CPU; one more is refused rather than dropped without a word.
TEST_F(GlTest, EveryLightUpToTheLimitIsDrawn) {
  lp::gl::Renderer r;
  r.setMesh(lp::makeUvSphere(512, 256));
  Sh9 L;
  L.c[0] = glm::vec3(0.2f);
  std::vector<lp::Light> lights(lp::kMaxLights);
  for (int i = 0; i < lp::kMaxLights; ++i) {
    const float a = 2.0f * glm::pi<float>() * float(i) / float(lp::kMaxLights);
    lights[i].dir = glm::normalize(glm::vec3(std::cos(a), std::sin(a), i % 2 ? 0.5f : -0.3f));
    lights[i].angularRadius = glm::radians(2.0f);
    lights[i].power = glm::vec3(1.0f + 0.25f * float(i));
  }
  r.setLighting(L, lights);
  for (int trial = 0; trial < 4; ++trial) {
    lp::gl::Camera cam;
    cam.yawDeg = 90.0f * trial;
    const auto px = pass(r, cam, OutputMode::Irradiance);
    const double worst =
        worstAgainstCpu(cam, px, [&](glm::vec3 n) { return lp::evalIrradiance(L, lights, n); });
    EXPECT_LT(worst, 2e-3) << "trial " << trial;
  }
  lights.push_back(lights[0]);
  EXPECT_THROW(r.setLighting(L, lights), std::invalid_argument);
}

// --shadows --ground: the shadow of a unit sphere on the ground plane falls where geometry puts
// it. The darkened region (shadows on against off: everything else is equal) matches, pixel by
// pixel, the ground points whose ray towards the sun hits the sphere (this test's own ray
// casting), and its centroid lies on the ray from the sun through the sphere's centre.
TEST_F(GlTest, SunShadowFallsWhereGeometryPutsIt) {
  lp::gl::Renderer r;
  r.setMesh(lp::makeUvSphere(512, 256));
  Sh9 L;
  L.c[0] = glm::vec3(0.3f);
  std::vector<lp::Light> lights(1);
  lights[0].dir = glm::normalize(glm::vec3(0.3f, -0.6f, 0.74f));  // R&H world
  lights[0].angularRadius = glm::radians(0.27f);
  lights[0].power = glm::vec3(3.0f);
  r.setLighting(L, lights);
  const glm::vec3 sun = lp::axes::glFromWorld(lights[0].dir);  // GL frame, towards the sun
  auto check = [&](const lp::gl::Camera& cam, const std::string& name) {
    auto render = [&](bool shadows) {
      lp::gl::FloatTarget target(kSize, kSize);
      target.bind();
      lp::gl::ShadingSettings s;
      s.toneMap = lp::gl::ToneMap::Linear;
      s.exposure = 0.5f;
      s.ground = true;
      s.shadows = shadows;
      r.draw({kSize, kSize}, cam, s);
      return target.readRgba();
    };
    const auto lit = render(false), shadowed = render(true);
    saveDisplay(shadowed, name);
    glm::dvec2 cRendered(0), cExpected(0);
    double nRendered = 0, nExpected = 0, both = 0;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        glm::vec3 o;
        const glm::vec3 d = pixelRayGl(cam, x, y, &o);
        const float b = glm::dot(o, d), disc = b * b - (glm::dot(o, o) - 1.0f);
        if (disc >= 0 || d.y >= 0) continue;  // the sphere itself, or above the horizon
        const glm::vec3 p = o + ((-1.0f - o.y) / d.y) * d;  // on the ground plane y = -1
        const float along = -glm::dot(p, sun);              // (c - p) . sun, c = 0
        const bool expected = along > 0 && glm::length(-p - along * sun) < 1.0f;
        const std::size_t i = 4 * (std::size_t(y) * kSize + x);
        const bool rendered = shadowed[i + 1] < 0.8f * lit[i + 1];
        if (expected) cExpected += glm::dvec2(x, y), ++nExpected;
        if (rendered) cRendered += glm::dvec2(x, y), ++nRendered;
        both += expected && rendered;
      }
    EXPECT_GT(nExpected, 500) << name;
    cExpected /= nExpected, cRendered /= nRendered;
    EXPECT_LT(glm::length(cRendered - cExpected), 2.0) << name << ": centroids, pixels";
    EXPECT_GT(both / (nExpected + nRendered - both), 0.9) << name << ": intersection over union";
    return cRendered;
  };
  lp::gl::Camera side;
  side.yawDeg = 20.0f, side.pitchDeg = 35.0f, side.distance = 5.0f;
  check(side, "shadow_sphere.png");
  // Seen facing the sun, in the vertical plane of the ray from the sun through the centre,
  // what the sphere hides of its shadow is symmetric about that plane: the darkened region's
  // centroid, taken back to the ground, lies on the ray's ground track.
  lp::gl::Camera along;
  along.yawDeg = glm::degrees(std::atan2(-sun.x, -sun.z)), along.pitchDeg = 60.0f;
  along.distance = 5.0f;
  const glm::dvec2 c = check(along, "shadow_sphere_facing_sun.png");
  glm::vec3 o;
  const glm::vec3 d = pixelRayGl(along, int(c.x), int(c.y), &o);
  const glm::vec3 p = o + ((-1.0f - o.y) / d.y) * d;
  const glm::vec2 track = glm::normalize(glm::vec2(sun.x, sun.z));  // the ray's ground direction
  const float lateral = std::abs(p.x * track.y - p.z * track.x);    // distance from the track
  EXPECT_LT(lateral, 0.03f) << "the centroid is " << lateral << " off the sun ray's track";
  // The penumbra follows the angular radius: the ground pixels between shadow and light (30-70%
  // of the lit value) are many more for an 8-degree sun than for the real sun's 0.27 degrees.
  auto penumbra = [&](float radiusDeg) {
    lights[0].angularRadius = glm::radians(radiusDeg);
    r.setLighting(L, lights);
    int n = 0;
    for (const bool on : {false, true}) {
      lp::gl::FloatTarget target(kSize, kSize);
      target.bind();
      lp::gl::ShadingSettings s;
      s.toneMap = lp::gl::ToneMap::Linear, s.exposure = 0.5f, s.ground = true, s.shadows = on;
      r.draw({kSize, kSize}, side, s);
      static std::vector<float> off;
      const auto px = target.readRgba();
      if (!on) {
        off = px;
        continue;
      }
      for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
          glm::vec3 o;
          const glm::vec3 d = pixelRayGl(side, x, y, &o);
          const float b = glm::dot(o, d);
          if (b * b - (glm::dot(o, o) - 1.0f) >= 0) continue;  // the ground only
          const std::size_t i = 4 * (std::size_t(y) * kSize + x) + 1;
          const auto linear = [](float v) {  // the display pass writes sRGB
            return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
          };
          const float ratio = linear(px[i]) / linear(off[i]);
          n += ratio > 0.3f && ratio < 0.7f;
        }
    }
    return n;
  };
  const int sharp = penumbra(0.27f), soft = penumbra(8.0f);
  EXPECT_GT(soft, 4 * sharp) << "penumbra pixels: sharp " << sharp << ", soft " << soft;
}

// The restatement's figures 3-6: one coefficient at a time, on the sphere and the bunny. The
// normal pass tells where each pixel faces; the display pass is what the user sees.
struct Single {
  const char* name;
  float value;
};

class SingleCoefficient : public GlTest, public ::testing::WithParamInterface<const char*> {};

TEST_P(SingleCoefficient, PaperFigures) {
  const std::string model = GetParam();
  lp::Mesh mesh =
      model == "sphere" ? lp::makeUvSphere() : lp::loadMesh(lpt::dataPath("models/" + model));
  lp::fitToUnitSphere(mesh);
  mesh.albedo = glm::vec3(1.0f);
  lp::gl::Renderer r;
  r.setMesh(mesh);
  lp::gl::Camera cam;
  const Single figs[] = {{"L00", 0.5f}, {"L10", 0.05f}, {"L20", -0.2f}, {"L22", -0.06f}};
  const auto normals = pass(r, cam, OutputMode::Normal);
  for (const auto& f : figs) {
    Sh9 L;
    L.c[std::size_t(lp::shIndex(f.name))] = glm::vec3(f.value);
    r.setLighting(L);
    // Exposure: the brightest irradiance on the sphere maps to 0.9 (linear tone map).
    float peak = 0;
    for (int i = 0; i < 20000; ++i) {
      const float z = 1 - 2 * (i + 0.5f) / 20000, p = 2.39996f * i, s = std::sqrt(1 - z * z);
      peak = std::max(peak, lp::evalIrradiance(L, {s * std::cos(p), s * std::sin(p), z}).x);
    }
    const auto img = pass(r, cam, OutputMode::Display, 0.9f * std::numbers::pi_v<float> / peak);
    saveDisplay(img, std::string("fig_") + f.name + "_" + model + ".png");
    // Mean displayed value over pixels whose world normal satisfies `pred`.
    auto meanWhere = [&](auto pred) {
      double sum = 0;
      int n = 0;
      for (int i = 0; i < kSize * kSize; ++i) {
        if (normals[4 * i + 3] == 0) continue;  // background
        const glm::vec3 nw(normals[4 * i], normals[4 * i + 1], normals[4 * i + 2]);
        if (glm::length(nw) < 0.5f || !pred(nw)) continue;
        sum += img[4 * i];
        ++n;
      }
      EXPECT_GT(n, 30) << f.name << " " << model << ": too few pixels for a region";
      return sum / std::max(n, 1);
    };
    const std::string name = f.name;
    if (name == "L00") {
      float lo = 1, hi = 0;
      for (int i = 0; i < kSize * kSize; ++i)
        if (normals[4 * i + 3] != 0 &&
            glm::length(glm::vec3(normals[4 * i], normals[4 * i + 1], normals[4 * i + 2])) > 0.5f)
          lo = std::min(lo, img[4 * i]), hi = std::max(hi, img[4 * i]);
      EXPECT_LT(hi - lo, 1.5f / 255) << "L00 must be uniform on " << model;
      EXPECT_GT(lo, 0.5f);
    } else if (name == "L10") {  // brighter at the top (+z) than at the bottom
      EXPECT_GT(meanWhere([](glm::vec3 n) { return n.z > 0.5f; }),
                meanWhere([](glm::vec3 n) { return n.z < -0.5f; }) + 0.3)
          << model;
    } else if (name == "L20") {  // negative: darker at the poles than at the equator
      EXPECT_LT(meanWhere([](glm::vec3 n) { return std::abs(n.z) > 0.8f; }) + 0.2,
                meanWhere([](glm::vec3 n) { return std::abs(n.z) < 0.3f; }))
          << model;
    } else {  // L22 < 0: the x^2 - y^2 pattern, bright towards +-y, dark towards +-x
      EXPECT_GT(meanWhere([](glm::vec3 n) { return std::abs(n.y) > 0.7f; }),
                meanWhere([](glm::vec3 n) { return std::abs(n.x) > 0.7f; }) + 0.2)
          << model;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Models, SingleCoefficient,
                         ::testing::Values("sphere", "stanford-bunny.obj"), [](const auto& info) {
                           return std::string(info.param) == "sphere" ? "sphere" : "bunny";
                         });

// An equirect with one bright disc around world direction `dir`, dim grey elsewhere.
lp::Image spotEnvironment(glm::vec3 dir) {
  lp::Image img(512, 256);
  for (int i = 0; i < img.height; ++i)
    for (int j = 0; j < img.width; ++j) {
      const float t = std::numbers::pi_v<float> * (i + 0.5f) / img.height;
      const float p = 2 * std::numbers::pi_v<float> * (j + 0.5f) / img.width;
      const glm::vec3 d(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
      const float v = glm::dot(d, dir) > std::cos(glm::radians(3.0f)) ? 200.0f : 0.02f;
      float* px = img.pixel(j, i);
      px[0] = px[1] = px[2] = v;
    }
  return img;
}

// Light direction: the spot as seen in the background and the brightest point of the sphere
// agree within a few degrees.
TEST_F(GlTest, LightComesFromTheSpotInTheBackground) {
  const glm::vec3 spot = glm::normalize(glm::vec3(-0.8f, -0.35f, 0.45f));  // world
  const lp::Image env = spotEnvironment(spot);
  lp::gl::Renderer r;
  r.setMesh(lp::makeUvSphere(256, 128));
  r.setLighting(lp::project(
      lp::PanoramaView::rgbF32(env.rgb.data(), env.width, env.height, lp::Layout::Equirect)));
  r.setBackground(env.rgb.data(), env.width, env.height, lp::gl::BackgroundMapping::Equirect);

  // 1. Find the spot in the background from a camera looking its way past the sphere.
  const glm::vec3 spotGl = lp::axes::glFromWorld(spot);
  lp::gl::Camera look;
  look.yawDeg = glm::degrees(std::atan2(-spotGl.x, -spotGl.z));
  look.pitchDeg = -glm::degrees(std::asin(spotGl.y)) - 12.0f;  // the spot sits above the sphere
  look.distance = 6.0f;
  const auto bg = pass(r, look, OutputMode::Display, 1.0f, true);
  saveDisplay(bg, "light_direction_background.png");
  double sx = 0, sy = 0, sw = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x)
      if (bg[4 * (y * kSize + x)] > 0.99f) sx += x, sy += y, sw += 1;
  ASSERT_GT(sw, 3) << "the spot is not visible in the background";
  glm::vec3 o;
  const glm::vec3 seen = lp::axes::worldFromGl(pixelRayGl(look, int(sx / sw), int(sy / sw), &o));
  EXPECT_GT(glm::dot(seen, spot), std::cos(glm::radians(2.0f))) << "background orientation";

  // 2. The brightest point of the sphere, seen from the spot's side.
  lp::gl::Camera front;
  front.yawDeg = glm::degrees(std::atan2(spotGl.x, spotGl.z)) + 25.0f;
  front.pitchDeg = glm::degrees(std::asin(spotGl.y));
  const auto e = pass(r, front, OutputMode::Irradiance);
  float best = -1;
  glm::vec3 brightest(0);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      glm::vec3 n;
      if (!sphereNormal(front, x, y, &n, 0.05f)) continue;
      if (e[4 * (y * kSize + x) + 1] > best) best = e[4 * (y * kSize + x) + 1], brightest = n;
    }
  const float angle =
      glm::degrees(std::acos(std::min(1.0f, glm::dot(lp::axes::worldFromGl(brightest), seen))));
  EXPECT_LT(angle, 3.0f) << "brightest point of the sphere vs the spot in the background";
}

// The documented default view: the equirect's centre column (world -x) is straight ahead, and
// world +z is up on the screen.
TEST_F(GlTest, DefaultViewOrientation) {
  lp::gl::Renderer r;
  const lp::Image ahead = spotEnvironment({-1, 0, 0});
  r.setBackground(ahead.rgb.data(), ahead.width, ahead.height, lp::gl::BackgroundMapping::Equirect);
  auto img = pass(r, lp::gl::Camera{}, OutputMode::Display, 1.0f, true);
  EXPECT_GT(img[4 * (kSize / 2 * kSize + kSize / 2)], 0.99f) << "world -x should be at the centre";
  const lp::Image up = spotEnvironment(glm::normalize(glm::vec3(-1, 0, 0.25f)));
  r.setBackground(up.rgb.data(), up.width, up.height, lp::gl::BackgroundMapping::Equirect);
  img = pass(r, lp::gl::Camera{}, OutputMode::Display, 1.0f, true);
  int above = 0, below = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x)
      if (img[4 * (y * kSize + x)] > 0.99f) (y < kSize / 2 ? above : below)++;
  EXPECT_GT(above, 0);
  EXPECT_EQ(below, 0);
}

}  // namespace
