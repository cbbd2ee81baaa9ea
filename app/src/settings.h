#pragma once
// What the command line asks for, as typed settings: one struct per concern, each field bound to
// its option where the option is declared (OptionSpec::set, through the builders below). The
// value is parsed and checked when the command line is read, so a bad value is one line before
// anything runs, and no command reads an option by its name.
#include <array>
#include <cstdint>
#include <glm/vec3.hpp>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "args.h"
#include "liveprobe/capture/v4l2.h"
#include "liveprobe/exchange/engine_export.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/gl/renderer.h"
#include "liveprobe/sh/layout.h"

namespace lp::cli {

using Size = std::pair<int, int>;
using Triple = std::array<double, 3>;

/// The panorama's layout and orientation (layoutOptions).
struct PanoramaSettings {
  std::optional<Layout> layout;
  std::optional<Triple> circle;      ///< cx, cy, r in pixels
  bool circleAuto = false;           ///< --circle auto: found in the image (capture/ball.h)
  std::optional<double> fov;         ///< degrees
  std::optional<std::string> lens;   ///< --lens FILE: a lens calibration
  std::optional<UnseenRule> unseen;  ///< --unseen RULE
  std::optional<Triple> rotate;      ///< yaw, pitch, roll in degrees
  bool flip = false;
};

/// The compact lights taken out of the coefficients (lightOptionSpecs).
struct LightSettings {
  bool sun = false;
  std::optional<int> count;  ///< --lights K
};

/// --coeff NAME=VALUE: one coefficient (index in liveprobe/sh/sh.h's order) and its value.
struct CoeffAssignment {
  int index = 0;
  glm::vec3 value{0.0f};
};

/// Where a still's lighting comes from (lightingOptions).
struct LightingSettings {
  std::optional<std::string> env, coeffs;
  std::vector<CoeffAssignment> coeff;  ///< each name at most once
};

/// The model, the camera and the look (sceneOptions).
/// Where a frame is projected (--projection).
enum class ProjectOn : std::uint8_t { Auto, Cpu, Gpu };

struct SceneSettings {
  std::string model = "sphere";
  std::optional<Triple> modelRotate;
  bool upZ = false;
  std::optional<double> yaw, pitch, distance;
  std::optional<double> exposure;           ///< nullopt: auto
  gl::ToneMap toneMap = gl::ToneMap::Aces;  ///< --tonemap
  bool tonemapBackground = false, noBackground = false, fullResolution = false;
  bool shadows = false, ground = false, headless = false;
  int msaa = 4;
  gl::Backend gl = gl::Backend::Auto;      ///< --gl
  int gpu = -1;                            ///< --gpu: an EGL device (-1: the first GPU)
  ProjectOn projection = ProjectOn::Auto;  ///< --projection
};

/// What a command writes and how much it runs.
struct OutputSettings {
  std::optional<std::string> out, jsonFile, plot, screenshot, outDir, outVideo, coeffsOut;
  std::string saveCoeffs = "coeffs-edited.json";
  std::optional<CoeffFormat> format;  ///< --format: what a command prints (none: its default)
  CoeffFormat coeffsFormat;           ///< --coeffs-format
  std::optional<Size> size;
  std::optional<std::int64_t> frames;
  std::optional<double> duration;
  bool hud = false, noHud = false, quiet = false;
};

/// A stream's decoding, pacing and processing, and where its records go (streamOptions).
struct StreamSettings {
  std::optional<double> gamma;  ///< nullopt: sRGB
  double inputExposure = 1.0;
  double smooth = 0.0;
  std::optional<double> fps;
  int reduce = 1;
  int threads = 2;
  bool loop = false, realtime = false;
  std::optional<std::string> serve;
  bool serveRemote = false;
  std::optional<int> serveClients, serveIdle;
  std::optional<std::string> publish, mqttCafile, mqttPasswordFile, response, record;
  double holdBelow = 0.0;
};

/// What live and calibrate do with a camera besides opening it (the device's own settings are
/// capture's lp::CameraSettings, Settings::camera: --pixel-format, --mjpeg-reduce, --timeout;
/// its size and rate are --size and --fps).
struct LiveSettings {
  std::optional<Size> viewSize;         ///< --view-size
  std::optional<double> lockExposure;   ///< seconds to settle, when --lock-exposure is given
  std::optional<std::string> metadata;  ///< --metadata (none: the node after the device's)
  std::vector<double> bracket;          ///< stops, when given
  double reconnect = 10;                ///< --reconnect: the longest wait between tries, s
  std::string rtspTransport = "tcp";    ///< --rtsp-transport
  std::array<double, 2> stops = {-6, 3};
  int settle = 8;
};

/// calibrate-lens: the board and the lens model.
struct LensCalibrationSettings {
  std::optional<Size> board;     ///< --board COLSxROWS (inner corners)
  std::optional<double> square;  ///< --square SIZE
  std::string model = "fisheye";
  std::optional<std::string> device;  ///< --device: boards from a live camera
  int boards = 20;                    ///< --boards: how many the camera keeps
};

/// --window: the band window against ringing.
struct WindowChoice {
  enum class Kind : std::uint8_t { None, Auto, Cmgen, Hann } kind = Kind::None;
  double width = 0;  ///< Hann's, above 2
};

/// coeffs, irradiance and compare.
struct StillSettings {
  WindowChoice window;
  std::optional<int> cube;
  bool brute = false;  ///< irradiance --method brute (else sh)
};

/// bench.
struct BenchSettings {
  int repeat = 3;
  double threshold = 25.0;
  double maxContention = 1.5;  ///< above it (over the baseline's) a slower stage is inconclusive
  std::optional<std::string> baseline;
  std::vector<std::pair<int, double>> injectDelay;  ///< --inject-delay STAGE=MS: bench stage, ms
};

struct Settings {
  PanoramaSettings panorama;
  LightSettings lights;
  LightingSettings lighting;
  SceneSettings scene;
  OutputSettings output;
  StreamSettings stream;
  CameraSettings camera;  ///< the V4L2 camera's (cameraOptions; device, size and rate at open)
  LiveSettings live;
  StillSettings still;
  BenchSettings bench;
  LensCalibrationSettings lensCalibration;
};

// The parsers behind the builders: each throws lp::Error "NAME VALUE: expected ..." (one line).
struct Range {
  double lo, hi;
  bool aboveLo = false;  ///< lo itself is refused
};
/// "1 to 64", or "above 0 and up to 1000".
std::string rangeText(const Range& r);
double parseNumberIn(const std::string& name, const std::string& v, const Range& r);
std::int64_t parseIntegerIn(const std::string& name, const std::string& v, std::int64_t lo,
                            std::int64_t hi);
Triple parseTriple(const std::string& name, const std::string& v, const std::string& expected);
std::string parseChoice(const std::string& name, const std::string& v,
                        const std::vector<std::string>& choices);
/// "a|b|c" and "a, b or c".
std::string joinChoices(const std::vector<std::string>& choices, const std::string& separator);

template <class T>
struct OptionalValue {
  using type = T;
};
template <class T>
struct OptionalValue<std::optional<T>> {
  using type = T;
};

/// A field of Settings, for the builders: LP_FIELD(lights.sun).
#define LP_FIELD(path) \
  [](::lp::cli::Settings & s_) -> auto& { return s_.path; }

/// An option's declaration, before its field is bound.
inline OptionSpec declared(std::string name, std::string value, std::string help,
                           std::string group) {
  return {std::move(name), std::move(value), std::move(help), false, false, std::move(group)};
}
/// "help (RANGE, default D)".
inline std::string withRange(const std::string& help, const std::string& range,
                             const std::string& dflt) {
  return help + " (" + range + (dflt.empty() ? "" : ", default " + dflt) + ")";
}

/// The builders: an option, its help text (a range or a default said from the same values the
/// parser checks), and the typed field it sets.
template <class F>
OptionSpec flagOption(std::string name, std::string help, F field, std::string group = {}) {
  OptionSpec o = declared(std::move(name), "", std::move(help), std::move(group));
  o.set = [field](Settings& s, const std::string&) { field(s) = true; };
  return o;
}

template <class F>
OptionSpec textOption(std::string name, std::string value, std::string help, F field,
                      std::string group = {}, bool repeatable = false) {
  OptionSpec o{std::move(name), std::move(value), std::move(help), repeatable,
               false,           std::move(group)};
  if constexpr (std::is_same_v<std::decay_t<decltype(field(std::declval<Settings&>()))>,
                               std::vector<std::string>>)
    o.set = [field](Settings& s, const std::string& v) { field(s).push_back(v); };
  else
    o.set = [field](Settings& s, const std::string& v) { field(s) = v; };
  return o;
}

/// An output file whose extension must be one of `extensions` (".png", ...).
template <class F>
OptionSpec fileOption(std::string name, std::string value, std::string help,
                      std::vector<std::string> extensions, F field, std::string group = {}) {
  OptionSpec o = declared(name, std::move(value), std::move(help), std::move(group));
  o.set = [name, extensions, field](Settings& s, const std::string& v) {
    requireExtension(v, name, extensions);
    field(s) = v;
  };
  return o;
}

template <class F>
OptionSpec integerOption(std::string name, std::string value, std::string help, std::int64_t lo,
                         std::int64_t hi, const std::string& dflt, F field,
                         std::string group = {}) {
  OptionSpec o =
      declared(name, std::move(value),
               withRange(help, std::to_string(lo) + " to " + std::to_string(hi), dflt), group);
  o.set = [name, lo, hi, field](Settings& s, const std::string& v) {
    using T = std::decay_t<decltype(field(s))>;
    using Value = typename OptionalValue<T>::type;
    field(s) = Value(parseIntegerIn(name, v, lo, hi));
  };
  return o;
}

template <class F>
OptionSpec numberOption(std::string name, std::string value, std::string help, Range r,
                        const std::string& dflt, F field, std::string group = {}) {
  OptionSpec o = declared(name, std::move(value), withRange(help, rangeText(r), dflt), group);
  o.set = [name, r, field](Settings& s, const std::string& v) {
    field(s) = parseNumberIn(name, v, r);
  };
  return o;
}

/// WxH, each side 1 to `maxSide`.
template <class F>
OptionSpec sizeOption(std::string name, std::string help, int maxSide, const std::string& dflt,
                      F field, std::string group = {}) {
  OptionSpec o = declared(
      name, "WxH", withRange(help, "each side up to " + std::to_string(maxSide), dflt), group);
  o.set = [name, maxSide, field](Settings& s, const std::string& v) {
    field(s) = parseSize(v, name, maxSide);
  };
  return o;
}

/// Three numbers, "a,b,c"; `expected` says what they are ("yaw,pitch,roll in degrees").
template <class F>
OptionSpec tripleOption(std::string name, std::string value, std::string help, std::string expected,
                        F field, std::string group = {}) {
  OptionSpec o = declared(name, std::move(value), std::move(help), std::move(group));
  o.set = [name, expected, field](Settings& s, const std::string& v) {
    field(s) = parseTriple(name, v, expected);
  };
  return o;
}

struct AsText {
  const std::string& operator()(const std::string& v) const { return v; }
};

/// One of `choices`, stored as `convert` makes it; the placeholder lists them.
template <class F, class C = AsText>
OptionSpec choiceOption(std::string name, std::string help, std::vector<std::string> choices,
                        const std::string& dflt, F field, std::string group = {}, C convert = {}) {
  OptionSpec o = declared(name, joinChoices(choices, "|"),
                          help + (dflt.empty() ? "" : " (default " + dflt + ")"), group);
  o.set = [name, choices, field, convert](Settings& s, const std::string& v) {
    field(s) = convert(parseChoice(name, v, choices));
  };
  return o;
}

}  // namespace lp::cli
