#include "liveprobe/exchange/coeffs_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include "liveprobe/frame/input_file.h"
#include "liveprobe/sh/error.h"

namespace lp {

double jsonFloat(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", double(v));
  // Shortest of 6..9 significant digits that reads back as the same float.
  for (int digits = 6; digits <= 9; ++digits) {
    char b[32];
    std::snprintf(b, sizeof b, "%.*g", digits, double(v));
    if (std::strtof(b, nullptr) == v) return std::strtod(b, nullptr);
  }
  return std::strtod(buf, nullptr);
}

nlohmann::ordered_json coefficientsJson(const Sh9& radiance) {
  nlohmann::ordered_json c = nlohmann::ordered_json::object();
  for (int k = 0; k < kShCount; ++k) {
    const Rgb v = radiance.c[k];
    c[std::string(kShNames[k])] = {jsonFloat(v.x), jsonFloat(v.y), jsonFloat(v.z)};
  }
  return c;
}

nlohmann::ordered_json lightsJson(const std::vector<Light>& lights) {
  nlohmann::ordered_json a = nlohmann::ordered_json::array();
  for (const Light& l : lights) {
    nlohmann::ordered_json j;
    j["direction"] = {jsonFloat(l.dir.x), jsonFloat(l.dir.y), jsonFloat(l.dir.z)};
    j["angular_radius_deg"] = jsonFloat(glm::degrees(l.angularRadius));
    j["power"] = {jsonFloat(l.power.x), jsonFloat(l.power.y), jsonFloat(l.power.z)};
    j["share"] = jsonFloat(l.share);
    j["clipped"] = l.clipped;
    a.push_back(std::move(j));
  }
  return a;
}

Sh9 coefficientsFromJson(const nlohmann::json& j, const std::string& source) {
  // An engine's export is for that engine: liveprobe reads its own coefficients.
  const auto exported = [&](const std::string& what) {
    return Error(source + ": " + what +
                 ", not liveprobe's coefficients (write those with coeffs --format json, the "
                 "default)");
  };
  if (j.is_object() && j.contains("format") && j["format"].is_string())
    throw exported("an export for " + j["format"].get<std::string>() + " (--format " +
                   j["format"].get<std::string>() + ")");
  if (j.is_object() && j.contains("asset")) throw exported("a glTF document (--format gltf)");
  const nlohmann::json& c = j.contains("coefficients") ? j["coefficients"] : j;
  if (!c.is_object()) throw Error(source + ": no \"coefficients\" object");
  Sh9 out;
  for (int k = 0; k < kShCount; ++k) {
    const std::string name(kShNames[k]);
    if (!c.contains(name)) throw Error(source + ": coefficient " + name + " is missing");
    const auto& v = c[name];
    if (!v.is_array() || v.size() != 3)
      throw Error(source + ": coefficient " + name + " must be an array [r, g, b]");
    for (int ch = 0; ch < 3; ++ch) {
      if (!v[ch].is_number()) throw Error(source + ": coefficient " + name + " has a non-number");
      const double x = v[ch].get<double>();
      if (!std::isfinite(x)) throw Error(source + ": coefficient " + name + " is not finite");
      if (std::abs(x) > kMaxLightingValue)
        throw Error(source + ": coefficient " + name + " is " + formatNumber(x) +
                    "; the most liveprobe takes is " + formatNumber(kMaxLightingValue));
      out.c[k][ch] = float(x);
    }
  }
  for (auto it = c.begin(); it != c.end(); ++it)
    if (shIndex(it.key()) < 0)
      throw Error(source + ": unknown coefficient name " + it.key() + " (expected L00 .. L22)");
  return out;
}

std::string lightText(const Light& l) {
  char b[256];
  std::snprintf(b, sizeof b,
                "direction (%.4f, %.4f, %.4f), radius %.2f deg, power %.6g %.6g %.6g, %.1f%% of "
                "the power%s",
                l.dir.x, l.dir.y, l.dir.z, glm::degrees(l.angularRadius), l.power.x, l.power.y,
                l.power.z, 100 * l.share, l.clipped ? " (clipped: a lower bound)" : "");
  return b;
}

namespace {
glm::vec3 finiteTriple(const nlohmann::json& v, const std::string& what) {
  if (!v.is_array() || v.size() != 3) throw Error(what + " must be an array of three numbers");
  glm::vec3 out;
  for (int i = 0; i < 3; ++i) {
    if (!v[i].is_number()) throw Error(what + " has a non-number");
    const double x = v[i].get<double>();
    if (!std::isfinite(x)) throw Error(what + " is not finite");
    if (std::abs(x) > kMaxLightingValue)
      throw Error(what + " is " + formatNumber(x) + "; the most liveprobe takes is " +
                  formatNumber(kMaxLightingValue));
    out[i] = float(x);
  }
  return out;
}
}  // namespace

std::vector<Light> lightsFromJson(const nlohmann::json& j, const std::string& source) {
  std::vector<Light> lights;
  if (!j.is_object() || !j.contains("lights")) return lights;
  const auto& a = j["lights"];
  if (!a.is_array()) throw Error(source + ": \"lights\" must be an array");
  if (a.size() > std::size_t(kMaxLights))
    throw Error(source + ": " + std::to_string(a.size()) + " lights; liveprobe draws at most " +
                std::to_string(kMaxLights));
  for (std::size_t i = 0; i < a.size(); ++i) {
    const std::string what = source + ": light " + std::to_string(i + 1);
    const auto& o = a[i];
    if (!o.is_object() || !o.contains("direction") || !o.contains("power"))
      throw Error(what + " needs \"direction\" and \"power\"");
    Light l;
    const glm::vec3 d = finiteTriple(o["direction"], what + " direction");
    const float len = glm::length(d);
    if (!(len > 1e-6f) || !std::isfinite(len)) throw Error(what + " direction has no length");
    l.dir = d / len;
    l.power = finiteTriple(o["power"], what + " power");
    if (l.power.x < 0 || l.power.y < 0 || l.power.z < 0) throw Error(what + " power is negative");
    if (o.contains("angular_radius_deg")) {
      const auto& r = o["angular_radius_deg"];
      if (!r.is_number() || !(r.get<double>() >= 0.0 && r.get<double>() <= 90.0))
        throw Error(what + " angular_radius_deg must be a number in [0, 90]");
      l.angularRadius = glm::radians(float(r.get<double>()));
    }
    if (o.contains("share") && o["share"].is_number())  // a fraction: kept in [0, 1]
      l.share = float(std::clamp(o["share"].get<double>(), 0.0, 1.0));
    if (o.contains("clipped") && o["clipped"].is_boolean()) l.clipped = o["clipped"].get<bool>();
    lights.push_back(l);
  }
  return lights;
}

Sh9 loadCoefficients(const std::string& path, std::vector<Light>* lights) {
  const std::string text = readInputFile(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);  // the whole file: trailing text is an error
  } catch (const nlohmann::json::exception& e) {
    throw Error(path + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  if (lights) *lights = lightsFromJson(j, path);
  return coefficientsFromJson(j, path);
}

std::string coefficientsText(const Sh9& radiance) {
  std::ostringstream s;
  char line[128];
  std::snprintf(line, sizeof line, "%-5s %14s %14s %14s\n", "name", "red", "green", "blue");
  s << line;
  for (int k = 0; k < kShCount; ++k) {
    std::snprintf(line, sizeof line, "%-5s %14.6g %14.6g %14.6g\n",
                  std::string(kShNames[k]).c_str(), double(radiance.c[k].x),
                  double(radiance.c[k].y), double(radiance.c[k].z));
    s << line;
  }
  return s.str();
}

std::string coefficientsGlsl(const Sh9& radiance) {
  const auto m = irradianceMatrices(radiance);
  std::ostringstream s;
  s << "// Irradiance matrices (Ramamoorthi & Hanrahan 2001, eq. 12), R&H frame (+z up).\n"
       "// E(n) = dot(vec4(n, 1.0), M * vec4(n, 1.0)) per channel; diffuse = albedo * E / pi.\n";
  const char* names[3] = {"shMatR", "shMatG", "shMatB"};
  char num[32];
  for (int ch = 0; ch < 3; ++ch) {
    s << "const mat4 " << names[ch] << " = mat4(";
    for (int col = 0; col < 4; ++col)
      for (int row = 0; row < 4; ++row) {
        std::snprintf(num, sizeof num, "%.9g", double(m[ch][col][row]));
        s << num << (col == 3 && row == 3 ? "" : ", ");
      }
    s << ");\n";
  }
  return s.str();
}

}  // namespace lp
