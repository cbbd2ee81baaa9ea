#pragma once
// Text forms of the nine radiance coefficients: JSON (the interchange format of every
// liveprobe command), a readable table, and a GLSL snippet with the three R&H matrices.
#include <nlohmann/json.hpp>
#include <string>

#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/sh.h"

namespace lp {

/// The largest magnitude of a coefficient or a light's power that liveprobe reads: the shaders'
/// sums of products of such values stay far inside float's range (3.4e38), where values near it
/// overflow to infinity and draw black.
inline constexpr double kMaxLightingValue = 1e30;

/// {"L00": [r,g,b], "L1-1": [...], ..., "L22": [...]} in storage order.
nlohmann::ordered_json coefficientsJson(const Sh9& radiance);

/// [{"direction": [x,y,z], "angular_radius_deg": a, "power": [r,g,b], "share": s,
///   "clipped": false}, ...]: the lights beside the coefficients, in the same world frame (R&H,
/// +z up) and units (power: radiance times steradians, the irradiance facing the light).
nlohmann::ordered_json lightsJson(const std::vector<Light>& lights);

/// Reads the "coefficients" object of a coefficients document (or a bare coefficients object).
/// Throws lp::Error naming `source` for a missing name, a non-numeric or non-finite value.
Sh9 coefficientsFromJson(const nlohmann::json& j, const std::string& source);

/// One light as a line of text: "direction (x, y, z), radius R deg, power r g b, S% of the
/// power" (and " (clipped: a lower bound)").
std::string lightText(const Light& light);

/// Reads the optional "lights" array beside the coefficients (lightsJson's form; none: empty).
/// Throws lp::Error naming `source` for a malformed light: a direction that is not three finite
/// numbers of non-zero length, a radius outside [0, 90] degrees, a power not three finite numbers
/// at or above zero.
std::vector<Light> lightsFromJson(const nlohmann::json& j, const std::string& source);

/// Reads a coefficients JSON file: {"coefficients": coefficientsJson, "lights": lightsJson} (the
/// lights optional) or a bare coefficients object; its lights, if any, into `lights`.
Sh9 loadCoefficients(const std::string& path, std::vector<Light>* lights = nullptr);

std::string coefficientsText(const Sh9& radiance);
std::string coefficientsGlsl(const Sh9& radiance);

/// A float as a JSON number with the shortest decimal form that round-trips the float.
double jsonFloat(float v);

}  // namespace lp
