// The scene's options: model, camera, look, the GL context, the lighting and the layout.
#include "commands.h"
#include "environment.h"
#include "liveprobe/sh/error.h"
#include "scene.h"
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
                    "the first GPU", LP_FIELD(scene.gpu), group),
      choiceOption("--projection",
                   "where frames are projected: on the GPU that draws (the frame uploaded, a "
                   "compute pass; a stream's in a headless EGL context of the capture thread's "
                   "own), on the CPU, or auto: the GPU where the context is a GPU with compute "
                   "shaders (not a software rasterizer), else the CPU",
                   {"auto", "cpu", "gpu"}, "auto", LP_FIELD(scene.projection), group,
                   [](const std::string& v) {
                     return v == "cpu"   ? ProjectOn::Cpu
                            : v == "gpu" ? ProjectOn::Gpu
                                         : ProjectOn::Auto;
                   })};
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
                   LP_FIELD(scene.toneMap), l,
                   [](const std::string& v) {
                     return v == "reinhard" ? gl::ToneMap::Reinhard
                            : v == "linear" ? gl::ToneMap::Linear
                                            : gl::ToneMap::Aces;
                   }),
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

namespace {
/// An option whose value one of the core's parsers reads, its error said with the option's name.
template <class Parse, class F>
OptionSpec parsedOption(const std::string& name, std::string value, std::string help,
                        const std::string& group, Parse parse, F field) {
  OptionSpec o = declared(name, std::move(value), std::move(help), group);
  o.set = [name, parse, field](Settings& s, const std::string& v) {
    try {
      field(s) = parse(v);
    } catch (const Error& e) {
      throw Error(name + ": " + std::string(e.what()));
    }
  };
  return o;
}
}  // namespace

std::vector<OptionSpec> layoutOptions() {
  const std::string g = "Panorama";
  OptionSpec layout = parsedOption(
      "--layout", "equirect|angular|mirrorball|cube|fisheye|lens",
      "panorama layout (default equirect; lens with --lens)", g,
      [](const std::string& v) { return parseLayout(v); }, LP_FIELD(panorama.layout));
  OptionSpec circle = tripleOption(
      "--circle", "CX,CY,R|auto",
      "mirrorball: the ball's circle in pixels, or auto: found in the image (a stream: followed "
      "from frame to frame)",
      "cx,cy,r with r > 0, or auto", LP_FIELD(panorama.circle), g);
  circle.set = [](Settings& s, const std::string& v) {
    s.panorama.circleAuto = v == "auto";
    s.panorama.circle.reset();
    if (s.panorama.circleAuto) return;
    const Triple c = parseTriple("--circle", v, "cx,cy,r with r > 0, or auto");
    if (!(c[2] > 0)) throw Error("--circle " + v + ": expected cx,cy,r with r > 0, or auto");
    s.panorama.circle = c;
  };
  OptionSpec unseen = parsedOption(
      "--unseen", "ground[=ALBEDO]|mean|black",
      "what fills the directions the frame does not see (a lens's): a ground of that albedo lit "
      "by the seen sky, the edge's mean, or nothing (default ground=0.2)",
      g, [](const std::string& v) { return parseUnseen(v); }, LP_FIELD(panorama.unseen));
  return {layout,
          circle,
          numberOption("--fov", "DEG", "fisheye: field of view of each lens", {180, 360}, "190",
                       LP_FIELD(panorama.fov), g),
          textOption("--lens", "FILE",
                     "lens: the camera's calibration (OpenCV FileStorage YAML/JSON or ROS "
                     "camera_info; implies --layout lens); mirrorball: the camera filming the "
                     "ball, traced as it is",
                     LP_FIELD(panorama.lens), g),
          unseen,
          tripleOption("--env-rotate,--rotate", "YAW,PITCH,ROLL",
                       "turn the environment, lighting and background together (degrees, about "
                       "+z, +y, +x)",
                       "yaw,pitch,roll in degrees", LP_FIELD(panorama.rotate), g),
          flagOption("--env-flip",
                     "the panorama is stored upside down: mirror it top to bottom (before "
                     "--env-rotate)",
                     LP_FIELD(panorama.flip), g)};
}

std::vector<OptionSpec> lightingOptions() {
  std::vector<OptionSpec> o = {
      textOption("--env", "FILE", "environment map that lights the model and is drawn behind it",
                 LP_FIELD(lighting.env))};
  for (auto& l : layoutOptions()) o.push_back(l);
  OptionSpec coeff = declared("--coeff", "NAME=VALUE",
                              "set one coefficient (VALUE or r,g,b), others zero; repeatable", {});
  coeff.repeatable = true;
  coeff.set = [](Settings& s, const std::string& v) {
    const CoeffAssignment c = parseCoeffAssignment(v);
    for (const CoeffAssignment& given : s.lighting.coeff)
      if (given.index == c.index)
        throw Error("--coeff " + v + ": " + v.substr(0, v.find('=')) + " is given twice");
    s.lighting.coeff.push_back(c);
  };
  o.insert(o.end(), {textOption("--coeffs", "FILE.json",
                                "coefficients (and lights) written by liveprobe coeffs",
                                LP_FIELD(lighting.coeffs)),
                     coeff});
  for (auto& l : lightOptionSpecs()) o.push_back(l);
  return o;
}

}  // namespace lp::cli
