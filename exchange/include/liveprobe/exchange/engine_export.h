#pragma once
// The coefficients and lights in each engine's convention (liveprobe/sh/engines.h says the
// frames and forms), and the one serializer of a frame's record: a coefficients log's lines,
// the WebSocket stream's and MQTT's messages are all frameRecord().
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "liveprobe/capture/image.h"
#include "liveprobe/capture/processed_frame.h"
#include "liveprobe/sh/engines.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/lights.h"

namespace lp {

/// json (liveprobe's own, R&H frame), text, glsl, or one engine's.
struct CoeffFormat {
  std::string name = "json";
  std::optional<Engine> engine;  ///< set for the engine formats
};

/// Parses a format name given to `flag`. `perFrame`: a record's format (json or an engine other
/// than gltf, whose document carries images); otherwise any of them.
CoeffFormat parseCoeffFormat(const std::string& name, const std::string& flag, bool perFrame);

/// The names, for help texts: "json|text|glsl|three|babylon|filament|unity|gltf|webxr".
std::string coeffFormatNames(bool perFrame);

/// The coefficients and lights as `engine` takes them (a JSON object; gltf excluded).
nlohmann::ordered_json engineJson(Engine engine, const Sh9& radiance,
                                  const std::vector<Light>& lights);

/// A glTF 2.0 document: EXT_lights_image_based with irradianceCoefficients and specular cube
/// images made from the environment (RGBD PNGs, embedded), and a KHR_lights_punctual
/// directional light per light.
nlohmann::ordered_json gltfDocument(const Image& panorama, const LayoutSpec& layout,
                                    const glm::mat3& worldFromFile, const Sh9& radiance,
                                    const std::vector<Light>& lights);

/// Timings of one frame beside its coefficients; negative: unknown (written as null or left out).
struct RecordTimes {
  double renderMs = -1;
  double shownLatencyMs = -1;
  GpuTimes gpu;  ///< the viewer's GPU times (upload, render) where it has a GPU timer
};

/// One frame's record, one line of JSON: frame, time, format, coefficients (and lights) in
/// `format`, stage timings and latency.
std::string frameRecord(const ProcessedFrame& f, const CoeffFormat& format, RecordTimes t);

}  // namespace lp
