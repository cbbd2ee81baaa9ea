#include "liveprobe/hdr/response.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "liveprobe/frame/input_file.h"
#include "liveprobe/frame/srgb.h"
#include "liveprobe/sh/error.h"

namespace lp {

CameraResponse CameraResponse::srgb() {
  CameraResponse r;
  r.name = "sRGB";
  for (auto& ch : r.linear)
    for (int i = 0; i < 256; ++i) ch[std::size_t(i)] = srgbToLinear(float(i) / 255.0f);
  return r;
}

CameraResponse CameraResponse::gamma(float g) {
  CameraResponse r;
  char name[32];
  std::snprintf(name, sizeof name, "gamma %g", double(g));
  r.name = name;
  for (auto& ch : r.linear)
    for (int i = 0; i < 256; ++i) ch[std::size_t(i)] = std::pow(float(i) / 255.0f, g);
  return r;
}

int CameraResponse::firstDecrease(int* channel) const {
  for (int c = 0; c < 3; ++c)
    for (int i = 1; i < 256; ++i)
      if (!(linear[std::size_t(c)][std::size_t(i)] >= linear[std::size_t(c)][std::size_t(i - 1)])) {
        if (channel) *channel = c;
        return i;
      }
  return -1;
}

std::string CameraResponse::json() const {
  nlohmann::json j;
  j["response"] = nlohmann::json::array();
  for (const auto& ch : linear) j["response"].push_back(std::vector<float>(ch.begin(), ch.end()));
  if (readFrom != 0 || readTo != 255) j["read"] = {readFrom, readTo};
  if (controlDelay) j["control_delay_frames"] = *controlDelay;
  return j.dump();
}

CameraResponse CameraResponse::parse(const std::string& text, const std::string& name) {
  CameraResponse r;
  r.name = name;
  try {
    const auto j = nlohmann::json::parse(text);
    const auto& a = j.at("response");
    if (!a.is_array() || a.size() != 3) throw Error("\"response\" must hold 3 curves (R, G, B)");
    for (std::size_t c = 0; c < 3; ++c) {
      if (!a[c].is_array() || a[c].size() != 256)
        throw Error("each curve must hold 256 values, one per 8-bit code");
      for (std::size_t i = 0; i < 256; ++i) {
        const double v = a[c][i].get<double>();
        if (!std::isfinite(v) || v < 0) throw Error("a value is negative or not finite");
        r.linear[c][i] = float(v);
      }
    }
    if (j.contains("read")) {
      const auto& read = j["read"];
      if (!read.is_array() || read.size() != 2)
        throw Error("\"read\" must be [from, to], the codes the calibration read");
      r.readFrom = read[0].get<int>(), r.readTo = read[1].get<int>();
      if (r.readFrom < 0 || r.readTo > 255 || r.readFrom >= r.readTo)
        throw Error("\"read\" must be two codes from 0 to 255, the first the lower");
    }
    if (j.contains("control_delay_frames")) {
      const auto& d = j["control_delay_frames"];
      if (!d.is_number_integer() || d.get<int>() < 0 || d.get<int>() > 60)
        throw Error("\"control_delay_frames\" must be a whole number of frames from 0 to 60");
      r.controlDelay = d.get<int>();
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(name + ": not a camera response (" + e.what() + ")");
  } catch (const Error& e) {
    throw Error(name + ": not a camera response: " + e.what());
  }
  int c = 0;
  if (const int at = r.firstDecrease(&c); at >= 0)
    throw Error(name + ": the response falls at code " + std::to_string(at) + " of channel " +
                "RGB"[c] + ": a response must not decrease");
  if (!(r.linear[1][255] > 0)) throw Error(name + ": the response is zero at code 255");
  return r;
}

CameraResponse CameraResponse::load(const std::string& path) {
  return parse(readInputFile(path), path);
}

PowerLaw fitPowerLaw(const std::function<double(int)>& linear) {
  // Least squares of log(linear) = log(atClip) + gamma log(code / 255) over codes 32..240.
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (int i = 32; i <= 240; ++i, ++n) {
    const double x = std::log(i / 255.0), y = std::log(std::max(linear(i), 1e-30));
    sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  PowerLaw p;
  p.gamma = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  p.atClip = std::exp((sy - p.gamma * sx) / n);
  return p;
}

}  // namespace lp
