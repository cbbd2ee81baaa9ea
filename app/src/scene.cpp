#include "scene.h"

#include <sstream>

#include "capture/error.h"
#include "capture/frame.h"
#include "capture/photometry.h"
#include "coeffs_io.h"

namespace lp::cli {

std::vector<OptionSpec> sceneOptions() {
  return {{"--model", "FILE|sphere", "model to light (OBJ, PLY, glTF, ...; default: a UV sphere)"},
          {"--yaw", "DEG", "camera yaw around the vertical axis (default 0: front view)"},
          {"--pitch", "DEG", "camera pitch (default 0)"},
          {"--distance", "D", "camera distance; the model fits the unit sphere (default 3.2)"},
          {"--exposure", "X|auto", "exposure multiplier; auto maps the mean radiance to 0.18 (default)"},
          {"--tonemap", "aces|reinhard|linear", "tone map (default aces)"},
          {"--no-background", "", "do not draw the panorama behind the model"},
          {"--headless", "", "render offscreen through OSMesa even when a display exists"}};
}

std::vector<OptionSpec> layoutOptions() {
  return {{"--layout", "equirect|angular|mirrorball|cube|fisheye", "panorama layout (default equirect)"},
          {"--circle", "CX,CY,R", "mirrorball: the ball's circle in pixels"},
          {"--fov", "DEG", "fisheye: field of view of each lens (default 190)"}};
}

LayoutSpec layoutFromArgs(const Args& a) {
  LayoutSpec spec(parseLayout(a.get("--layout", "equirect")));
  if (a.has("--circle")) {
    if (spec.layout != Layout::MirrorBall) throw Error("--circle applies to --layout mirrorball only");
    std::vector<float> v;
    std::stringstream s(a.get("--circle"));
    for (std::string part; std::getline(s, part, ',');) v.push_back(float(parseNumber(part, "--circle")));
    if (v.size() != 3 || !(v[2] > 0)) throw Error("--circle " + a.get("--circle") + ": expected cx,cy,r with r > 0");
    spec.circle = {v[0], v[1], v[2]};
  }
  if (a.has("--fov")) {
    if (spec.layout != Layout::DualFisheye) throw Error("--fov applies to --layout fisheye only");
    spec.fisheyeFovDeg = float(a.number("--fov", 190));
  }
  return spec;
}

Environment loadEnvironment(const std::string& source, const LayoutSpec& layout) {
  auto src = openSource(source);
  Frame frame;
  if (!src->next(frame)) throw Error(source + ": no frame to read");
  Environment env;
  env.layout = layout;
  Photometry photometry;
  photometry.exposure = float(src->radianceScale());
  Linearizer(photometry).convert(frame, env.image);
  if (auto why = layoutMismatch(layout, env.image.width, env.image.height); !why.empty())
    throw Error(source + ": " + why);
  env.radiance = Projector(layout, env.image.width, env.image.height).project(env.image.rgb.data());
  return env;
}

void setBackground(gl::Renderer& r, const Image& frame, const LayoutSpec& layout) {
  if (layout.layout == Layout::Equirect || layout.layout == Layout::Angular) {
    r.setBackground(frame.rgb.data(), frame.width, frame.height,
                    layout.layout == Layout::Angular ? gl::BackgroundMapping::Angular
                                                     : gl::BackgroundMapping::Equirect);
    return;
  }
  const Image eq = resampleToEquirect(frame, layout, 1024, 512);
  r.setBackground(eq.rgb.data(), eq.width, eq.height, gl::BackgroundMapping::Equirect);
}

void setBackground(gl::Renderer& r, const Frame& frame, const LayoutSpec& layout, float scale) {
  r.setBackgroundSrgb8(frame.bgr8.data(), frame.width, frame.height,
                       layout.layout == Layout::Angular ? gl::BackgroundMapping::Angular : gl::BackgroundMapping::Equirect,
                       scale);
}

std::vector<OptionSpec> lightingOptions() {
  std::vector<OptionSpec> o = {{"--env", "FILE", "environment map that lights the model and is drawn behind it"}};
  for (auto& l : layoutOptions()) o.push_back(l);
  o.insert(o.end(), {
          {"--coeffs", "FILE.json", "coefficients written by liveprobe coeffs"},
          {"--coeff", "NAME=VALUE", "set one coefficient (VALUE or r,g,b), others zero; repeatable",
           true}});
  return o;
}

void applyCoeffAssignment(const std::string& text, Sh9& sh) {
  const auto eq = text.find('=');
  if (eq == std::string::npos) throw Error("--coeff " + text + ": expected NAME=VALUE, e.g. L20=-0.2");
  const std::string name = text.substr(0, eq);
  const int k = shIndex(name);
  if (k < 0) throw Error("--coeff " + text + ": unknown coefficient name " + name + " (L00 .. L22)");
  std::vector<float> v;
  std::stringstream s(text.substr(eq + 1));
  for (std::string part; std::getline(s, part, ',');) v.push_back(float(parseNumber(part, "--coeff " + name)));
  if (v.size() == 1) v = {v[0], v[0], v[0]};
  if (v.size() != 3) throw Error("--coeff " + text + ": expected one value or r,g,b");
  sh.c[k] = {v[0], v[1], v[2]};
}

std::optional<Lighting> lightingFromArgs(const Args& a) {
  const int kinds = int(a.has("--env")) + int(a.has("--coeffs")) + int(a.has("--coeff"));
  if (kinds > 1) throw Error("give only one of --env, --coeffs and --coeff");
  if (kinds == 0) return std::nullopt;
  Lighting l;
  if (a.has("--env")) {
    Environment env = loadEnvironment(a.get("--env"), layoutFromArgs(a));
    l.layout = env.layout;
    l.radiance = env.radiance;
    l.background = std::move(env.image);
  } else if (a.has("--coeffs")) {
    l.radiance = loadCoefficients(a.get("--coeffs"));
  } else {
    for (const auto& c : a.all("--coeff")) applyCoeffAssignment(c, l.radiance);
  }
  return l;
}

Mesh meshFromArgs(const Args& a) {
  const std::string model = a.get("--model", "sphere");
  Mesh m;
  if (model == "sphere") {
    m = makeUvSphere();
  } else {
    try {
      m = loadMesh(model);
    } catch (const MeshError& e) {
      throw Error(e.what());
    }
  }
  fitToUnitSphere(m);
  return m;
}

gl::Camera cameraFromArgs(const Args& a) {
  gl::Camera c;
  c.yawDeg = float(a.number("--yaw", c.yawDeg));
  c.pitchDeg = float(a.number("--pitch", c.pitchDeg));
  c.distance = float(a.number("--distance", c.distance));
  if (!(c.distance > 0.05f)) throw Error("--distance " + a.get("--distance") + ": must be > 0.05");
  if (std::abs(c.pitchDeg) > 89.9f) throw Error("--pitch " + a.get("--pitch") + ": must be within +-89.9");
  return c;
}

float autoExposure(const Sh9& radiance) {
  const float meanRadiance = luminance(radiance.c[0]) * 0.282095f;
  return meanRadiance > 1e-12f ? 0.18f / meanRadiance : 1.0f;
}

gl::ShadingSettings shadingFromArgs(const Args& a, const Sh9& radiance) {
  gl::ShadingSettings s;
  const std::string e = a.get("--exposure", "auto");
  s.exposure = e == "auto" ? autoExposure(radiance) : float(parseNumber(e, "--exposure"));
  if (!(s.exposure > 0)) throw Error("--exposure " + e + ": must be positive or auto");
  const std::string tm = a.get("--tonemap", "aces");
  if (tm == "aces") s.toneMap = gl::ToneMap::Aces;
  else if (tm == "reinhard") s.toneMap = gl::ToneMap::Reinhard;
  else if (tm == "linear") s.toneMap = gl::ToneMap::Linear;
  else throw Error("--tonemap " + tm + ": expected aces, reinhard or linear");
  s.background = !a.has("--no-background");
  return s;
}

gl::Backend backendFromArgs(const Args& a) {
  return a.has("--headless") ? gl::Backend::Headless : gl::Backend::Auto;
}

std::unique_ptr<gl::GlContext> openContext(gl::Backend backend, std::pair<int, int> size) {
  try {
    return gl::createGlContext({backend, size.first, size.second, "liveprobe", true});
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

void loadScene(gl::Renderer& r, const Mesh& mesh, const Lighting& lighting) {
  loadModel(r, mesh);
  r.setLighting(lighting.radiance);
  if (lighting.background) setBackground(r, *lighting.background, lighting.layout);
}

void applyInput(gl::Camera& camera, const gl::InputDelta& input) {
  camera.yawDeg -= 0.3f * input.drag.x;
  camera.pitchDeg = std::clamp(camera.pitchDeg + 0.3f * input.drag.y, -89.0f, 89.0f);
  camera.distance = std::clamp(camera.distance * std::pow(0.9f, input.scroll), 1.1f, 50.0f);
}

}  // namespace lp::cli
