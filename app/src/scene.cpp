#include "scene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <sstream>

#include "commands.h"
#include "liveprobe/capture/frame.h"
#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/input_file.h"
#include "liveprobe/capture/photometry.h"
#include "liveprobe/capture/resample.h"
#include "liveprobe/exchange/coeffs_io.h"
#include "liveprobe/sh/error.h"
#include "progress.h"
#include "settings.h"

namespace lp::cli {

std::vector<OptionSpec> glOptions(const std::string& group) {
  return {
      choiceOption("--gl",
                   "which GL draws: a window, EGL (headless, on a GPU; on Mesa's llvmpipe where "
                   "there is none), OSMesa (headless, on the CPU), or auto: a window where "
                   "there is a display, else EGL on a GPU, else OSMesa",
                   {"auto", "window", "egl", "osmesa"}, "auto", LP_FIELD(scene.gl), group,
                   [](const std::string& v) {
                     return v == "window"   ? gl::Backend::Window
                            : v == "egl"    ? gl::Backend::Egl
                            : v == "osmesa" ? gl::Backend::OsMesa
                                            : gl::Backend::Auto;
                   }),
      integerOption("--gpu", "N",
                    "--gl egl: the EGL device to draw on (liveprobe --version lists them)", 0, 63,
                    "the first GPU", LP_FIELD(scene.gpu), group)};
}

std::vector<OptionSpec> sceneOptions() {
  const std::string m = "Model and camera", l = "Look";
  std::vector<OptionSpec> o = {
      textOption("--model", "FILE|sphere",
                 "model to light (OBJ, PLY, glTF, ...; default: a UV sphere)",
                 LP_FIELD(scene.model), m),
      tripleOption("--model-rotate", "YAW,PITCH,ROLL",
                   "turn the model (degrees, about its up, right and view axes)",
                   "yaw,pitch,roll in degrees", LP_FIELD(scene.modelRotate), m),
      choiceOption("--up", "the model file's up axis, y as in OBJ and glTF", {"y", "z"}, "y",
                   LP_FIELD(scene.upZ), m, [](const std::string& v) { return v == "z"; }),
      numberOption("--yaw", "DEG", "camera yaw around the vertical axis", {-360, 360},
                   "0: front view", LP_FIELD(scene.yaw), m),
      numberOption("--pitch", "DEG", "camera pitch", {-89.9, 89.9}, "0", LP_FIELD(scene.pitch), m),
      numberOption("--distance", "D", "camera distance; the model fits the unit sphere",
                   {0.05, 1000, true}, "3.2", LP_FIELD(scene.distance), m),
      [&] {
        OptionSpec o{"--exposure",
                     "X|auto",
                     "exposure multiplier, above 0; auto (default): mean radiance to 0.18, or from "
                     "the irradiance without an environment",
                     false,
                     false,
                     l};
        o.set = [](Settings& s, const std::string& v) {
          if (v == "auto")
            s.scene.exposure.reset();
          else if (!((s.scene.exposure = parseNumber(v, "--exposure")) > 0))
            throw Error("--exposure " + v + ": must be positive or auto");
        };
        return o;
      }(),
      choiceOption("--tonemap", "tone map", {"aces", "reinhard", "linear"}, "aces",
                   LP_FIELD(scene.tonemap), l),
      choiceOption("--msaa", "multisample anti-aliasing, samples per pixel", {"1", "2", "4", "8"},
                   "4", LP_FIELD(scene.msaa), l,
                   [](const std::string& v) { return std::stoi(v); })};
  const auto gl = glOptions(l);
  o.insert(o.end(), gl.begin(), gl.end());
  struct Flag {
    const char* name;
    const char* help;
    bool SceneSettings::*field;
  };
  for (const Flag& f : std::initializer_list<Flag>{
           {"--tonemap-background",
            "expose and tone-map an 8-bit background like HDR (default: shown as the source looks)",
            &SceneSettings::tonemapBackground},
           {"--no-background", "do not draw the panorama behind the model",
            &SceneSettings::noBackground},
           {"--full-resolution",
            "a window on a software GL (llvmpipe) keeps its full resolution and MSAA, however slow "
            "(default: dynamic resolution keeps about 30 frames/s)",
            &SceneSettings::fullResolution},
           {"--shadows",
            "the first light (--sun) casts the model's shadow, sharp or soft as its angular radius",
            &SceneSettings::shadows},
           {"--ground",
            "a shadow catcher under the model: the background darkened by its shadow and occlusion",
            &SceneSettings::ground},
           {"--headless",
            "render offscreen even when a display exists (EGL on a GPU, else OSMesa; --gl picks "
            "one)",
            &SceneSettings::headless}})
    o.push_back(flagOption(
        f.name, f.help, [field = f.field](Settings& s) -> bool& { return s.scene.*field; }, l));
  return o;
}

std::vector<OptionSpec> layoutOptions() {
  const std::string g = "Panorama";
  OptionSpec layout{"--layout",
                    "equirect|angular|mirrorball|cube|fisheye",
                    "panorama layout (default equirect)",
                    false,
                    false,
                    g};
  layout.set = [](Settings& s, const std::string& v) {
    try {
      s.panorama.layout = parseLayout(v);
    } catch (const Error& e) {
      throw Error("--layout: " + std::string(e.what()));
    }
  };
  OptionSpec circle = tripleOption("--circle", "CX,CY,R", "mirrorball: the ball's circle in pixels",
                                   "cx,cy,r with r > 0", LP_FIELD(panorama.circle), g);
  circle.set = [](Settings& s, const std::string& v) {
    const Triple c = parseTriple("--circle", v, "cx,cy,r with r > 0");
    if (!(c[2] > 0)) throw Error("--circle " + v + ": expected cx,cy,r with r > 0");
    s.panorama.circle = c;
  };
  return {layout, circle,
          numberOption("--fov", "DEG", "fisheye: field of view of each lens", {180, 360}, "190",
                       LP_FIELD(panorama.fov), g),
          tripleOption("--env-rotate,--rotate", "YAW,PITCH,ROLL",
                       "turn the environment, lighting and background together (degrees, about "
                       "+z, +y, +x)",
                       "yaw,pitch,roll in degrees", LP_FIELD(panorama.rotate), g),
          flagOption("--env-flip",
                     "the panorama is stored upside down: mirror it top to bottom (before "
                     "--env-rotate)",
                     LP_FIELD(panorama.flip), g)};
}

glm::mat3 envOrientation(const PanoramaSettings& p) {
  glm::mat3 o(1.0f);
  if (p.rotate) {
    const Triple& v = *p.rotate;
    o = rotationYawPitchRoll(float(v[0]), float(v[1]), float(v[2]));
  }
  if (p.flip) o = o * glm::mat3(glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, 0, -1));
  return o;
}

LayoutSpec layoutSpec(const PanoramaSettings& p, const FrameSource* source) {
  const bool known = source && source->layout();
  const Layout native = known ? *source->layout() : Layout::Equirect;
  LayoutSpec spec(native);
  if (p.layout) {
    spec.layout = *p.layout;
    if (known && spec.layout != native)
      throw Error(source->describe() + ": the frames are a " + std::string(layoutName(native)) +
                  " layout; --layout " + std::string(layoutName(*p.layout)) + " does not apply");
  }
  if (p.circle) {
    if (spec.layout != Layout::MirrorBall)
      throw Error("--circle applies to --layout mirrorball only");
    spec.circle = {float((*p.circle)[0]), float((*p.circle)[1]), float((*p.circle)[2])};
  } else if (spec.layout == Layout::MirrorBall) {
    throw Error(
        "--layout mirrorball needs --circle cx,cy,r: the mirror ball's centre and radius "
        "in pixels");
  }
  if (p.fov) {
    if (spec.layout != Layout::DualFisheye) throw Error("--fov applies to --layout fisheye only");
    spec.fisheyeFovDeg = float(*p.fov);
  }
  return spec;
}

Environment loadEnvironment(const std::string& source, const PanoramaSettings& p,
                            const LightOptions& lights) {
  layoutSpec(p);  // option errors before the file is read
  auto src = openSource(source);
  // One map: a sequence or a video is replayed, not read as its first frame.
  if (const std::int64_t n = src->frameCount(); n > 1)
    throw Error(source + ": " + std::to_string(n) +
                " frames (a sequence or a video), not one map: name one image, or replay it");
  Frame frame;
  if (!src->next(frame)) throw Error(source + ": no frame to read");
  Environment env;
  env.layout = layoutSpec(p, src.get());
  env.orientation = envOrientation(p);
  FrameProcessor processor({env.layout, Photometry{}, env.orientation, 1, lights});
  FrameLighting lit;
  try {
    processor.fit(frame);  // the tables, before the projection is timed
    const auto t0 = std::chrono::steady_clock::now();
    lit = processor.process(frame);
    env.projectMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  } catch (const Error& e) {
    throw Error(source + ": " + e.what());
  }
  env.radiance = lit.radiance;
  env.lights = std::move(lit.lights);
  env.whole = lit.whole;
  // The linear image, for what reads pixels (the brute force, the background, the glTF cube), in
  // the same units as the coefficients: the frame's own exposure applied.
  const float scale = float(frame.radianceScale);
  processor.linearizer().convert(frame, env.image);
  if (scale != 1.0f)
    for (float& v : env.image.rgb) v *= scale;
  if (frame.format == PanoramaFormat::BgrU8) env.displayScale = scale;
  warnIfLayoutLooksWrong(source, env.layout, p.layout.has_value(), env.image.width,
                         env.image.height, env.image.rgb.data());
  return env;
}

void warnIfLayoutLooksWrong(const std::string& source, const LayoutSpec& layout, bool given, int w,
                            int h, const float* rgb) {
  const bool guessedEquirect = layout.layout == Layout::Equirect && !given;
  if (guessedEquirect && w == h) {
    warn(source +
         ": a square image taken as equirect (an angular map or a mirror ball? give --layout)");
  } else if (guessedEquirect && std::abs(double(w) / h - 16.0 / 9.0) < 0.02) {
    warn(source +
         ": a 16:9 frame taken as equirect (a 2:1 panorama stretched to 16:9 covers the sphere: "
         "give --layout equirect; a camera's view does not)");
  } else if ((layout.layout == Layout::Angular || layout.layout == Layout::DualFisheye) && rgb &&
             w >= 16 && h >= 8) {
    // Outside its discs an angular map or a dual fisheye frame is black: compare the corners'
    // pixels (of each half, for two lenses) with the discs' centres.
    const bool dual = layout.layout == Layout::DualFisheye;
    const auto at = [&](int x, int y) {
      const float* p = rgb + 3 * (std::size_t(y) * std::size_t(w) + std::size_t(x));
      return double(p[0]) + p[1] + p[2];
    };
    std::vector<int> xs = {1, w - 2}, centres = {w / 2};
    if (dual) xs = {1, w / 2 - 2, w / 2 + 1, w - 2}, centres = {w / 4, 3 * w / 4};
    double corner = 0, centre = 0;
    for (const int cy : {1, h - 2})
      for (const int cx : xs) corner += at(cx, cy);
    for (const int cx : centres) centre += at(cx, h / 2);
    if (corner / double(2 * xs.size()) > 0.01 * std::max(centre / double(centres.size()), 1e-6))
      warn(source +
           (dual ? ": a dual fisheye frame whose corners are not black"
                 : ": an angular map whose corners are not black") +
           " (is it an equirect? give --layout)");
  }
}

namespace {
gl::BackgroundMapping backgroundMapping(Layout drawn) {
  if (drawn != Layout::Equirect && drawn != Layout::Angular)
    throw std::logic_error("the background is drawn from an equirect or an angular map");
  return drawn == Layout::Angular ? gl::BackgroundMapping::Angular
                                  : gl::BackgroundMapping::Equirect;
}
}  // namespace

void setBackground(gl::Renderer& r, const Image& panorama, Layout drawn, float displayScale) {
  r.setBackground(panorama.rgb.data(), panorama.width, panorama.height, backgroundMapping(drawn),
                  displayScale);
}

void setBackground(gl::Renderer& r, const Frame& frame, Layout drawn, float scale) {
  r.setBackgroundSrgb8(frame.bgr8.data(), frame.width, frame.height, backgroundMapping(drawn),
                       scale);
}

std::vector<OptionSpec> lightingOptions() {
  std::vector<OptionSpec> o = {
      textOption("--env", "FILE", "environment map that lights the model and is drawn behind it",
                 LP_FIELD(lighting.env))};
  for (auto& l : layoutOptions()) o.push_back(l);
  OptionSpec coeff = textOption("--coeff", "NAME=VALUE",
                                "set one coefficient (VALUE or r,g,b), others zero; repeatable",
                                LP_FIELD(lighting.coeff), {}, true);
  coeff.set = [](Settings& s, const std::string& v) {
    Sh9 check;
    applyCoeffAssignment(v, check);  // a bad name or value is refused as the line is read
    s.lighting.coeff.push_back(v);
  };
  o.insert(o.end(), {textOption("--coeffs", "FILE.json",
                                "coefficients (and lights) written by liveprobe coeffs",
                                LP_FIELD(lighting.coeffs)),
                     coeff});
  for (auto& l : lightOptionSpecs()) o.push_back(l);
  return o;
}

void applyCoeffAssignment(const std::string& text, Sh9& sh) {
  const auto eq = text.find('=');
  if (eq == std::string::npos)
    throw Error("--coeff " + text + ": expected NAME=VALUE, e.g. L20=-0.2");
  const std::string name = text.substr(0, eq);
  const int k = shIndex(name);
  if (k < 0)
    throw Error("--coeff " + text + ": unknown coefficient name " + name + " (L00 .. L22)");
  std::vector<float> v;
  std::stringstream s(text.substr(eq + 1));
  for (std::string part; std::getline(s, part, ',');) {
    const double x = parseNumber(part, "--coeff " + name);
    if (std::abs(x) > kMaxLightingValue)
      throw Error("--coeff " + text + ": the most liveprobe takes is " +
                  formatNumber(kMaxLightingValue));
    v.push_back(float(x));
  }
  if (v.size() == 1) v = {v[0], v[0], v[0]};
  if (v.size() != 3) throw Error("--coeff " + text + ": expected one value or r,g,b");
  sh.c[k] = {v[0], v[1], v[2]};
}

std::optional<Lighting> lightingFrom(const Settings& st) {
  const LightingSettings& ls = st.lighting;
  const int kinds = int(ls.env.has_value()) + int(ls.coeffs.has_value()) + int(!ls.coeff.empty());
  if (kinds > 1) throw Error("give only one of --env, --coeffs and --coeff");
  if (kinds == 0) return std::nullopt;
  const LightOptions lights = chooseLights(st);
  if (lights.maxLights > 0 && !ls.env)
    throw Error(
        "--sun and --lights take the lights out of an --env map (a --coeffs file carries "
        "its own)");
  Lighting l;
  if (ls.env) {
    Environment env = loadEnvironment(*ls.env, st.panorama, lights);
    l.lights = env.lights;
    l.layout = env.layout;
    l.orientation = env.orientation;
    l.displayScale = env.displayScale;
    l.radiance = env.radiance;
    l.background = std::move(env.image);
  } else {
    if (ls.coeffs) {
      l.radiance = loadCoefficients(*ls.coeffs, &l.lights);
    } else {
      std::vector<int> seen;
      for (const auto& c : ls.coeff) {
        Sh9 one;
        applyCoeffAssignment(c, one);
        const int k = shIndex(c.substr(0, c.find('=')));
        if (std::find(seen.begin(), seen.end(), k) != seen.end())
          throw Error("--coeff " + c + ": " + c.substr(0, c.find('=')) + " is given twice");
        seen.push_back(k);
        l.radiance.c[std::size_t(k)] = one.c[std::size_t(k)];
      }
    }
    LightSplit turned = rotateSplit({l.radiance, l.lights}, envOrientation(st.panorama));
    l.radiance = turned.residual;
    l.lights = std::move(turned.lights);
  }
  return l;
}

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
  s.toneMap = sc.tonemap == "reinhard" ? gl::ToneMap::Reinhard
              : sc.tonemap == "linear" ? gl::ToneMap::Linear
                                       : gl::ToneMap::Aces;
  s.background = !sc.noBackground;
  s.displayReferredBackground = !sc.tonemapBackground;
  s.shadows = sc.shadows;
  s.ground = sc.ground;
  s.samples = sc.msaa;
  return s;
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
  if (!lighting.background) return;
  if (displayDrawsAsIs(lighting.layout))
    setBackground(r, *lighting.background, lighting.layout.layout, lighting.displayScale);
  else
    setBackground(r, displayEquirect(*lighting.background, lighting.layout), Layout::Equirect,
                  lighting.displayScale);
}

}  // namespace lp::cli
