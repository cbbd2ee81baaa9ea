#include "liveprobe/exchange/engine_export.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "liveprobe/capture/image.h"
#include "liveprobe/exchange/coeffs_io.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/layout.h"

namespace lp {

namespace {

using ojson = nlohmann::ordered_json;

ojson triple(glm::vec3 v) { return {jsonFloat(v.x), jsonFloat(v.y), jsonFloat(v.z)}; }

/// 27 floats: r, g, b of each coefficient in liveprobe's order.
ojson flat27(const Sh9& sh) {
  ojson a = ojson::array();
  for (const Rgb& c : sh.c)
    for (int ch = 0; ch < 3; ++ch) a.push_back(jsonFloat(c[ch]));
  return a;
}

ojson nineTriples(const Sh9& sh) {
  ojson a = ojson::array();
  for (const Rgb& c : sh.c) a.push_back(triple(c));
  return a;
}

/// A light as colour (maximum 1) times intensity: the irradiance it gives a surface facing it.
struct ColorIntensity {
  glm::vec3 color{0.0f};
  float intensity = 0.0f;
};
ColorIntensity colorIntensity(glm::vec3 power) {
  const float m = std::max({power.x, power.y, power.z});
  if (!(m > 0.0f)) return {};
  return {power / m, m};
}

/// A light's direction (towards it) in the engine's frame.
glm::vec3 towards(const Light& l, Engine e) { return glm::normalize(engineFromWorld(e) * l.dir); }

// ---- glTF: RGBD cube faces -------------------------------------------------------------------

/// RGBD, as EXT_lights_image_based's 4-channel PNGs hold HDR (Babylon's packing, which its
/// reader, the extension's reference, undoes): alpha D = clamp(floor(max(255 / max(rgb), 1)) /
/// 255, 1/255, 1), colour (rgb D)^(1/2.2); a reader raises the colour to 2.2 and divides by D.
/// Babylon's RGBD shaders use the power 2.2, not the sRGB curve: with the sRGB curve a texel at
/// 1% reads 37% dark.
void packRgbd(glm::vec3 c, std::uint8_t* out) {
  const float m = std::max({c.x, c.y, c.z, 1e-6f});
  const float d = std::clamp(std::floor(std::max(255.0f / m, 1.0f)) / 255.0f, 1.0f / 255.0f, 1.0f);
  for (int ch = 0; ch < 3; ++ch)
    out[ch] =
        std::uint8_t(std::lround(255.0f * std::pow(std::clamp(c[ch] * d, 0.0f, 1.0f), 1 / 2.2f)));
  out[3] = std::uint8_t(std::lround(255.0f * d));
}

std::string base64(const std::vector<std::uint8_t>& b) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string s;
  s.reserve((b.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < b.size(); i += 3) {
    const std::uint32_t v = std::uint32_t(b[i]) << 16 |
                            (i + 1 < b.size() ? std::uint32_t(b[i + 1]) << 8 : 0u) |
                            (i + 2 < b.size() ? std::uint32_t(b[i + 2]) : 0u);
    s += k[v >> 18 & 63];
    s += k[v >> 12 & 63];
    s += i + 1 < b.size() ? k[v >> 6 & 63] : '=';
    s += i + 2 < b.size() ? k[v & 63] : '=';
  }
  return s;
}

/// Solid angle of the part of a cube face (at distance 1) from its centre to (x, y).
double faceArea(double x, double y) { return std::atan2(x * y, std::sqrt(x * x + y * y + 1)); }

/// The environment's radiance on the six faces of a cube, n x n each, in GL's face order (rows:
/// t). Every panorama pixel's power (radiance times solid angle) lands on the cube whole, so
/// the cube holds the map's energy and coefficients however small its bright sources: each
/// texel takes kSub x kSub point samples, and a pixel's power is shared among the samples that
/// fall on it by their solid angles; a pixel no sample falls on (a few-pixel sun between
/// samples) gives its power to the texel its centre falls in. A box filter: no GGX
/// prefiltering.
std::vector<std::vector<glm::vec3>> radianceCube(const Image& image, const LayoutSpec& layout,
                                                 const glm::mat3& worldFromFile, int n) {
  constexpr int kSub = 4;
  const int m = n * kSub;
  const std::vector<SphereSample> pixels = layoutSamples(layout, image.width, image.height);
  const glm::mat3 fileFromWorld = glm::transpose(worldFromFile);
  // Each sample's pixel (-1: none) and solid angle, face by face, row by row.
  std::vector<std::int64_t> hit(std::size_t(6) * m * m, -1);
  std::vector<float> omega(hit.size());
  std::vector<double> hitOmega(pixels.size(), 0.0);
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < m; ++y)
      for (int x = 0; x < m; ++x) {
        const double x0 = 2.0 * x / m - 1, x1 = 2.0 * (x + 1) / m - 1;
        const double y0 = 2.0 * y / m - 1, y1 = 2.0 * (y + 1) / m - 1;
        const std::size_t at = (std::size_t(f) * m + y) * m + x;
        omega[at] =
            float(faceArea(x0, y0) - faceArea(x0, y1) - faceArea(x1, y0) + faceArea(x1, y1));
        const glm::vec3 d = glm::normalize(cubeFaceDirection(f, (x + 0.5) / m, (y + 0.5) / m));
        const auto px = layoutPixel(layout, image.width, image.height, fileFromWorld * d);
        if (!px) continue;
        const std::int64_t p =
            std::int64_t(std::clamp(int(px->y), 0, image.height - 1)) * image.width +
            std::clamp(int(px->x), 0, image.width - 1);
        if (!(pixels[std::size_t(p)].solidAngle > 0)) continue;
        hit[at] = p;
        hitOmega[std::size_t(p)] += omega[at];
      }
  const auto radiance = [&](std::int64_t p) {
    const float* c = &image.rgb[std::size_t(p) * 3];
    return glm::dvec3(c[0], c[1], c[2]);
  };
  // Power per texel, and each texel's solid angle.
  std::vector<glm::dvec3> power(std::size_t(6) * n * n, glm::dvec3(0.0));
  std::vector<double> texelOmega(power.size(), 0.0);
  const auto texelOf = [&](int f, int y, int x) {
    return (std::size_t(f) * n + y / kSub) * n + x / kSub;
  };
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < m; ++y)
      for (int x = 0; x < m; ++x) {
        const std::size_t at = (std::size_t(f) * m + y) * m + x, t = texelOf(f, y, x);
        texelOmega[t] += omega[at];
        if (const std::int64_t p = hit[at]; p >= 0)
          power[t] += radiance(p) * (double(pixels[std::size_t(p)].solidAngle) * omega[at] /
                                     hitOmega[std::size_t(p)]);
      }
  // The pixels no sample fell on: the cube layout's own cross (4 x 3 faces of m) finds the
  // sample their centre falls in.
  constexpr int kFaceOfCell[3][4] = {{-1, 2, -1, -1}, {1, 4, 0, 5}, {-1, 3, -1, -1}};
  for (std::size_t p = 0; p < pixels.size(); ++p) {
    if (hitOmega[p] > 0 || !(pixels[p].solidAngle > 0)) continue;
    const auto c =
        layoutPixel(LayoutSpec(Layout::Cube), 4 * m, 3 * m, worldFromFile * pixels[p].dir);
    if (!c) continue;
    const int cx = std::clamp(int(c->x), 0, 4 * m - 1), cy = std::clamp(int(c->y), 0, 3 * m - 1);
    const int f = kFaceOfCell[cy / m][cx / m];
    if (f < 0) continue;
    power[texelOf(f, cy % m, cx % m)] += radiance(std::int64_t(p)) * double(pixels[p].solidAngle);
  }
  std::vector<std::vector<glm::vec3>> faces(6, std::vector<glm::vec3>(std::size_t(n) * n));
  for (int f = 0; f < 6; ++f)
    for (std::size_t i = 0; i < std::size_t(n) * n; ++i) {
      const std::size_t t = std::size_t(f) * n * n + i;
      faces[std::size_t(f)][i] = glm::vec3(power[t] / texelOmega[t]);
    }
  return faces;
}

std::vector<glm::vec3> halve(const std::vector<glm::vec3>& f, int n) {
  const int h = n / 2;
  std::vector<glm::vec3> out(std::size_t(h) * h);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < h; ++j)
      out[std::size_t(i) * h + j] =
          0.25f *
          (f[std::size_t(2 * i) * n + 2 * j] + f[std::size_t(2 * i) * n + 2 * j + 1] +
           f[std::size_t(2 * i + 1) * n + 2 * j] + f[std::size_t(2 * i + 1) * n + 2 * j + 1]);
  return out;
}

/// A face (rows in GL's memory order: row 0 at t = 0) as an EXT_lights_image_based image, which
/// stores each face flipped top to bottom relative to that order (as Babylon.js's loader, the
/// extension's reference reader, uploads it).
std::string rgbdPngDataUri(const std::vector<glm::vec3>& face, int n) {
  std::vector<std::uint8_t> rgba(std::size_t(n) * n * 4);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      packRgbd(face[std::size_t(n - 1 - i) * n + j], &rgba[(std::size_t(i) * n + j) * 4]);
  return "data:image/png;base64," + base64(encodePng8(n, n, 4, rgba.data()));
}

}  // namespace

CoeffFormat parseCoeffFormat(const std::string& name, const std::string& flag, bool perFrame) {
  CoeffFormat f;
  f.name = name;
  f.engine = parseEngine(name);
  const bool ok = perFrame ? (name == "json" || (f.engine && *f.engine != Engine::Gltf))
                           : (name == "json" || name == "text" || name == "glsl" || f.engine);
  if (!ok)
    throw Error(flag + " " + name + ": expected " + coeffFormatNames(perFrame) +
                (perFrame && (name == "gltf" || name == "text" || name == "glsl")
                     ? " (a per-frame record is one JSON line; " + name + " is a still's format)"
                     : ""));
  return f;
}

std::string coeffFormatNames(bool perFrame) {
  return perFrame ? "json, three, babylon, filament, unity or webxr"
                  : "json, text, glsl, three, babylon, filament, unity, gltf or webxr";
}

namespace {

// One object per light under the engine's names: where its light travels (from the light
// towards the origin), its colour and its intensity.
ojson travellingLights(const std::vector<Light>& lights, Engine engine, const char* direction,
                       const char* colour) {
  ojson a = ojson::array();
  for (const Light& l : lights) {
    const ColorIntensity ci = colorIntensity(l.power);
    a.push_back({{direction, triple(-towards(l, engine))},
                 {colour, triple(ci.color)},
                 {"intensity", jsonFloat(ci.intensity)}});
  }
  return a;
}

// three.js: LightProbe.fromJSON({sh, intensity}); a DirectionalLight per light, placed along
// `direction` (it shines from there towards the origin), colour times intensity = the irradiance
// facing it.
ojson threeJson(const Sh9& L, const std::vector<Light>& lights) {
  ojson j;
  j["sh"] = flat27(L);
  j["intensity"] = 1;
  ojson a = ojson::array();
  for (const Light& l : lights) {
    const ColorIntensity ci = colorIntensity(l.power);
    a.push_back({{"direction", triple(towards(l, Engine::Three))},
                 {"color", triple(ci.color)},
                 {"intensity", jsonFloat(ci.intensity)},
                 {"angular_radius_deg", jsonFloat(glm::degrees(l.angularRadius))}});
  }
  j["directionalLights"] = a;
  return j;
}

// WebXR's XRLightProbe estimate: the coefficients and the primary light only.
ojson webXrJson(const Sh9& L, const std::vector<Light>& lights) {
  ojson j;
  j["sphericalHarmonicsCoefficients"] = flat27(L);
  if (!lights.empty()) {
    const glm::vec3 d = towards(lights[0], Engine::WebXr);
    const glm::vec3 p = lights[0].power;
    j["primaryLightDirection"] = {
        {"x", jsonFloat(d.x)}, {"y", jsonFloat(d.y)}, {"z", jsonFloat(d.z)}, {"w", 0}};
    j["primaryLightIntensity"] = {
        {"x", jsonFloat(p.x)}, {"y", jsonFloat(p.y)}, {"z", jsonFloat(p.z)}, {"w", 1}};
  }
  return j;
}

// Babylon.js: SphericalHarmonics (irradiance / pi, Condon-Shortley phase) and the
// SphericalPolynomial it derives; a DirectionalLight per light, whose direction is where the
// light travels.
ojson babylonJson(const Sh9& L, const std::vector<Light>& lights) {
  ojson j;
  Sh9 h = condonShortley(toIrradiance(L));
  h *= float(1.0 / kPi);
  static const char* names[kShCount] = {"l00",  "l1_1", "l10", "l11", "l2_2",
                                        "l2_1", "l20",  "l21", "l22"};
  ojson hj;
  for (int k = 0; k < kShCount; ++k) hj[names[k]] = triple(h.c[k]);
  j["harmonics"] = hj;
  const BabylonPolynomial p = babylonPolynomial(h);
  j["polynomial"] = {{"x", triple(p.x)},   {"y", triple(p.y)},   {"z", triple(p.z)},
                     {"xx", triple(p.xx)}, {"yy", triple(p.yy)}, {"zz", triple(p.zz)},
                     {"yz", triple(p.yz)}, {"zx", triple(p.zx)}, {"xy", triple(p.xy)}};
  j["directionalLights"] = travellingLights(lights, Engine::Babylon, "direction", "diffuse");
  return j;
}

// Filament: IndirectLight::Builder::irradiance(3, sh), pre-scaled; LightManager lights, SUN (the
// first) and DIRECTIONAL.
ojson filamentJson(const Sh9& L, const std::vector<Light>& lights) {
  ojson j;
  j["irradiance"] = nineTriples(preScaledIrradiance(L));
  ojson a = ojson::array();
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const ColorIntensity ci = colorIntensity(lights[i].power);
    ojson o;
    o["type"] = i == 0 ? "SUN" : "DIRECTIONAL";
    o["direction"] = triple(-towards(lights[i], Engine::Filament));
    o["color"] = triple(ci.color);
    o["intensity"] = jsonFloat(ci.intensity);
    if (i == 0) o["sunAngularRadius"] = jsonFloat(glm::degrees(lights[i].angularRadius));
    a.push_back(o);
  }
  j["lights"] = a;
  return j;
}

// Unity: SphericalHarmonicsL2[channel, coefficient], pre-scaled as Filament's; a Directional
// Light per light, whose transform.forward is where the light travels.
ojson unityJson(const Sh9& L, const std::vector<Light>& lights) {
  ojson j;
  const Sh9 s = preScaledIrradiance(L);
  ojson sh = ojson::array();
  for (int ch = 0; ch < 3; ++ch) {
    ojson row = ojson::array();
    for (int k = 0; k < kShCount; ++k) row.push_back(jsonFloat(s.c[k][ch]));
    sh.push_back(row);
  }
  j["sh"] = sh;
  j["lights"] = travellingLights(lights, Engine::Unity, "forward", "color");
  return j;
}

}  // namespace

ojson engineJson(Engine engine, const Sh9& radiance, const std::vector<Light>& lights) {
  const Sh9 L = toEngineFrame(radiance, engine);
  switch (engine) {
    case Engine::Three:
      return threeJson(L, lights);
    case Engine::WebXr:
      return webXrJson(L, lights);
    case Engine::Babylon:
      return babylonJson(L, lights);
    case Engine::Filament:
      return filamentJson(L, lights);
    case Engine::Unity:
      return unityJson(L, lights);
    case Engine::Gltf:
      break;
  }
  throw Error("gltf: a document, not a record (gltfDocument)");
}

ojson gltfDocument(const Image& panorama, const LayoutSpec& layout, const glm::mat3& worldFromFile,
                   const Sh9& radiance, const std::vector<Light>& lights) {
  const Sh9 L = toEngineFrame(radiance, Engine::Gltf);
  ojson doc;
  doc["asset"] = {{"version", "2.0"}, {"generator", "liveprobe coeffs --format gltf"}};
  ojson used = ojson::array({"EXT_lights_image_based"});
  if (!lights.empty()) used.push_back("KHR_lights_punctual");
  doc["extensionsUsed"] = used;
  // The specular cube: faces in OpenGL's order (+X -X +Y -Y +Z -Z), mips 64, 32 and 16.
  constexpr int kSize = 64, kMips = 3;
  ojson images = ojson::array(), mips = ojson::array();
  std::vector<std::vector<glm::vec3>> faces = radianceCube(panorama, layout, worldFromFile, kSize);
  // RGBD holds radiance up to 255: a brighter map is stored scaled down by a power of two, with
  // the light's intensity (which readers multiply into the cube and the coefficients) the scale.
  float peak = 0;
  for (const auto& face : faces)
    for (const glm::vec3& c : face) peak = std::max({peak, c.x, c.y, c.z});
  const float scale = peak > 255.0f ? std::exp2(std::ceil(std::log2(peak / 255.0f))) : 1.0f;
  for (auto& face : faces)
    for (glm::vec3& c : face) c /= scale;
  for (int m = 0, n = kSize; m < kMips; ++m, n /= 2) {
    ojson level = ojson::array();
    for (int f = 0; f < 6; ++f) {
      if (m > 0) faces[std::size_t(f)] = halve(faces[std::size_t(f)], n * 2);
      level.push_back(images.size());
      images.push_back(
          {{"uri", rgbdPngDataUri(faces[std::size_t(f)], n)}, {"mimeType", "image/png"}});
    }
    mips.push_back(level);
  }
  ojson light;
  light["name"] = "liveprobe";
  light["rotation"] = {0, 0, 0, 1};
  light["intensity"] = scale;
  light["irradianceCoefficients"] = nineTriples(condonShortley(toIrradiance(L) * (1.0f / scale)));
  light["specularImageSize"] = kSize;
  light["specularImages"] = mips;
  // What the extension's reference reader does with it (docs/engines.md: the fix, tested).
  light["extras"] = {
      {"liveprobe",
       "The light is in the glTF frame. Babylon.js shows its mirror image (in x in a left-handed "
       "scene, in z in a right-handed one) and multiplies the intensity into the coefficients "
       "twice; liveprobe's docs/engines.md gives the lines that undo both."}};
  ojson ext;
  ext["EXT_lights_image_based"] = {{"lights", ojson::array({light})}};
  ojson scene = {{"name", "liveprobe"},
                 {"extensions", {{"EXT_lights_image_based", {{"light", 0}}}}}};
  if (!lights.empty()) {
    // KHR_lights_punctual: a directional light shines along its node's -Z, lux = the
    // irradiance facing it. The node's rotation turns -Z to the direction the light travels.
    ojson punctual = ojson::array(), nodes = ojson::array(), sceneNodes = ojson::array();
    for (std::size_t i = 0; i < lights.size(); ++i) {
      const ColorIntensity ci = colorIntensity(lights[i].power);
      punctual.push_back({{"type", "directional"},
                          {"color", triple(ci.color)},
                          {"intensity", jsonFloat(ci.intensity)}});
      const glm::vec3 travel = -towards(lights[i], Engine::Gltf);
      // Quaternion taking (0, 0, -1) to `travel`.
      const glm::vec3 from(0, 0, -1);
      const float c = glm::dot(from, travel);
      glm::vec4 q;
      if (c < -0.999999f)
        q = {0, 1, 0, 0};  // opposite: half a turn about +y
      else {
        const glm::vec3 axis = glm::cross(from, travel);
        q = glm::normalize(glm::vec4(axis, 1.0f + c));
      }
      nodes.push_back(
          {{"name", "liveprobe light " + std::to_string(i + 1)},
           {"rotation", {jsonFloat(q.x), jsonFloat(q.y), jsonFloat(q.z), jsonFloat(q.w)}},
           {"extensions", {{"KHR_lights_punctual", {{"light", i}}}}}});
      sceneNodes.push_back(i);
    }
    ext["KHR_lights_punctual"] = {{"lights", punctual}};
    doc["nodes"] = nodes;
    scene["nodes"] = sceneNodes;
  }
  doc["extensions"] = ext;
  doc["images"] = images;
  doc["scene"] = 0;
  doc["scenes"] = ojson::array({scene});
  return doc;
}

std::string frameRecord(const ProcessedFrame& f, const CoeffFormat& format, RecordTimes t) {
  ojson j;
  j["frame"] = f.index;
  j["sequence"] = f.sequence;
  j["time"] = f.timestamp;
  if (format.engine) {
    j["format"] = format.name;
    j["coefficients"] = engineJson(*format.engine, f.radiance, f.lights);
  } else {
    j["coefficients"] = coefficientsJson(f.radiance);
    if (!f.lights.empty()) j["lights"] = lightsJson(f.lights);
  }
  // Capture's stages (merge and resample where they ran), and render: null where the frame was
  // not drawn.
  ojson tm;
  for (const Stage s : {Stage::Grab, Stage::Merge, Stage::Convert, Stage::Project, Stage::Resample})
    if (!stageRunsForSomeSources(s) || f.times[s] > 0) tm[std::string(stageName(s))] = f.times[s];
  tm["render"] = t.renderMs < 0 ? ojson(nullptr) : ojson(t.renderMs);
  // The GPU's own times, where there is a GPU timer (an earlier frame's: read late): capture's
  // projection, the viewer's upload and render.
  GpuTimes gpu = t.gpu;
  gpu.project = f.gpu.project;
  for (const auto& [key, member] : GpuTimes::kTimes)
    if (gpu.*member) tm[key] = *(gpu.*member);
  j["timings_ms"] = tm;
  const FrameConfidence& c = f.confidence;
  j["confidence"] = {{"value", c.value()},
                     {"clipped_share", c.clippedShare},
                     {"dark_share", c.darkShare},
                     {"brightest_measured", c.brightestMeasured},
                     {"agreement", c.agreement},
                     {"exposures", c.exposures},
                     {"complete", c.complete},
                     {"coverage", c.coverage},
                     {"held", f.held}};
  // Glass-to-light latency from the capture time (a camera's driver timestamp, or the grab of a
  // file's frame): to the coefficients, and to the frame that shows them.
  ojson l;
  l["coefficients"] = f.coefficientsLatencyMs;
  if (t.shownLatencyMs >= 0) l["shown"] = t.shownLatencyMs;
  j["latency_ms"] = l;
  if (f.reconnects > 0) j["reconnects"] = f.reconnects;
  // --circle auto in a stream: the followed mirror ball's circle this frame was projected with.
  if (f.ball)
    j["ball"] = {{"circle", {(*f.ball)[0], (*f.ball)[1], (*f.ball)[2]}}, {"lost", f.ballLost}};
  return j.dump();
}

}  // namespace lp
