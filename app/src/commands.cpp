#include "commands.h"

#include "liveprobe/backends.h"
#include "liveprobe/exchange/engine_export.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/sh/error.h"
#include "settings.h"

namespace lp::cli {

std::vector<OptionSpec> lightOptionSpecs(const std::string& group) {
  return {flagOption("--sun",
                     "take the dominant compact source (sun, lamp, window) out of the "
                     "coefficients and keep it as a disc light",
                     LP_FIELD(lights.sun), group),
          integerOption("--lights", "K", "up to K such lights, implying --sun", 1, kMaxLights, "1",
                        LP_FIELD(lights.count), group)};
}

OptionSpec threadsOption(const std::string& group) {
  return integerOption("--threads", "N", "threads for one frame's projection", 1, 64, "2",
                       LP_FIELD(stream.threads), group);
}

namespace opt {

OptionSpec size(const std::string& help, int maxSide, const std::string& dflt,
                const std::string& group) {
  return sizeOption("--size", help, maxSide, dflt, LP_FIELD(output.size), group);
}

OptionSpec out(const std::string& value, const std::string& help,
               const std::vector<std::string>& extensions, const std::string& group) {
  return fileOption("--out", value, help, extensions, LP_FIELD(output.out), group);
}

OptionSpec frames(const std::string& help, std::int64_t most, const std::string& dflt,
                  const std::string& group) {
  return integerOption("--frames", "N", help, 1, most, dflt, LP_FIELD(output.frames), group);
}

OptionSpec fps(const std::string& help, Range range, const std::string& dflt,
               const std::string& group) {
  return numberOption("--fps", "F", help, range, dflt, LP_FIELD(stream.fps), group);
}

OptionSpec duration(const std::string& help, const std::string& group) {
  return numberOption("--duration", "SECONDS", help, {0.001, 1e7}, "", LP_FIELD(output.duration),
                      group);
}

OptionSpec format(const std::string& help, const std::vector<std::string>& names,
                  const std::string& dflt, const std::string& group) {
  OptionSpec o = declared("--format", names.empty() ? "FORMAT" : joinChoices(names, "|"),
                          help + " (default " + dflt + ")", group);
  o.set = [names](Settings& s, const std::string& v) {
    if (!names.empty()) parseChoice("--format", v, names);
    s.output.format = parseCoeffFormat(v, "--format", false);
  };
  return o;
}

}  // namespace opt

OptionSpec quietOption(const std::string& group) {
  return flagOption("--quiet", "no progress on stderr", LP_FIELD(output.quiet), group);
}

std::vector<OptionSpec> hudOptions(const std::string& group, bool window) {
  std::vector<OptionSpec> o = {
      flagOption("--hud",
                 "draw the HUD (the panorama, the probes, the coefficients) into headless output "
                 "too",
                 LP_FIELD(output.hud), group)};
  if (window)
    o.push_back(flagOption("--no-hud", "start with the HUD hidden (H shows it)",
                           LP_FIELD(output.noHud), group));
  return o;
}

void checkHudOptions(const Settings& s) {
  if (s.output.hud && s.output.noHud) throw Error("--hud and --no-hud: give one of them");
}

LightOptions chooseLights(const Settings& s) {
  LightOptions o;
  o.maxLights = s.lights.count ? *s.lights.count : (s.lights.sun ? 1 : 0);
  return o;
}

const std::vector<Command>& commands() {
  static const std::vector<Command> all = {
      {kCoeffsSpec, runCoeffs,
       "the nine SH coefficients of an environment map (JSON, table, GLSL)"},
      {kIrradianceSpec, runIrradiance, "the irradiance map E(n), from SH or by brute force"},
      {kCompareSpec, runCompare,
       "SH irradiance against the brute-force integral (the paper's errors)"},
      {kRenderSpec, runRender, "one image of a model lit by the coefficients"},
      {kViewSpec, runView, "an interactive window (orbit, zoom)"},
      {kReplaySpec, runReplay, "a stream re-projected every frame, lighting a model"},
      {kRecordSpec, runRecord, "save a source for replay (FFV1 or MJPEG, with timestamps)"},
      {kLiveSpec, runLive, "a live light probe from a V4L2 or network camera"},
      {kDevicesSpec, runDevices, "list cameras: formats, sizes, frame rates, controls"},
      {kCalibrateSpec, runCalibrate, "a camera's response curve, for --response"},
      {kCalibrateLensSpec, runCalibrateLens,
       "a lens from chessboard photos or a live camera, for --lens"},
      {kBenchSpec, runBench, "frame-time regression run against a baseline"},
  };
  return all;
}

namespace {
struct BackendInfo {
  bool built;
  const char* name;    ///< as a sentence says it
  const char* label;   ///< as --version lists it
  const char* option;  ///< CMake's LIVEPROBE_WITH_*
};
BackendInfo backendInfo(OptionalBackend b) {
  switch (b) {
    case OptionalBackend::Window:
      return {LIVEPROBE_WITH_GLFW, "the GLFW window", "window (GLFW)", "LIVEPROBE_WITH_GLFW"};
    case OptionalBackend::V4l2:
      return {LIVEPROBE_WITH_V4L2, "V4L2 cameras", "V4L2 cameras", "LIVEPROBE_WITH_V4L2"};
    case OptionalBackend::Stream:
      return {LIVEPROBE_WITH_STREAM, "the WebSocket stream", "WebSocket stream",
              "LIVEPROBE_WITH_STREAM"};
    case OptionalBackend::Mqtt:
      return {LIVEPROBE_WITH_MQTT, "MQTT", "MQTT", "LIVEPROBE_WITH_MQTT"};
    case OptionalBackend::Network:
      return {LIVEPROBE_WITH_NETWORK, "network streams",
              "network streams, H.264 and HEVC cameras (FFmpeg)", "LIVEPROBE_WITH_NETWORK"};
  }
  return {false, "?", "?", "?"};
}
}  // namespace

bool builtIn(OptionalBackend b) { return backendInfo(b).built; }

void requireBackend(OptionalBackend b, const std::string& what, const std::string& instead) {
  const BackendInfo info = backendInfo(b);
  if (!info.built)
    throw Error((what.empty() ? "" : what + ": ") + "this liveprobe was built without " +
                info.name + " (" + info.option + ")" + (instead.empty() ? "" : "; " + instead));
}

std::string backendsLine() {
  std::string with, without;
  for (OptionalBackend b : {OptionalBackend::Window, OptionalBackend::V4l2, OptionalBackend::Stream,
                            OptionalBackend::Mqtt, OptionalBackend::Network}) {
    const BackendInfo info = backendInfo(b);
    std::string& list = info.built ? with : without;
    list += std::string(list.empty() ? "" : ", ") + info.label;
  }
  return (with.empty() ? "none" : with) + (without.empty() ? "" : "; built without " + without);
}

std::string glLine() {
  std::string line = LIVEPROBE_WITH_GLFW ? "window (GLFW)" : "";
  std::string projection;
  if (LIVEPROBE_WITH_EGL) {
    std::string devices;
    const auto list = gl::eglDevices();
    for (std::size_t i = 0; i < list.size(); ++i)
      devices += (i ? ", " : "") + std::to_string(i) + " " + list[i];
    line += std::string(line.empty() ? "" : ", ") +
            "EGL headless (devices: " + (devices.empty() ? "none" : devices) + ")";
    // --projection auto's choice where it draws headless: the first GPU (eglDevices() marks a
    // software rasterizer's device so).
    std::string gpu;
    for (std::size_t i = 0; i < list.size() && gpu.empty(); ++i)
      if (list[i] != "software" && list[i].find("(software)") == std::string::npos)
        gpu = "EGL device " + std::to_string(i);
    projection = "; --projection auto: " +
                 (gpu.empty() ? std::string("the CPU (no GPU among the EGL devices)")
                              : "the GPU headless (" + gpu + ")");
  }
  if (LIVEPROBE_WITH_OSMESA)
    line += std::string(line.empty() ? "" : ", ") + "OSMesa headless (CPU)";
  return (line.empty() ? "none" : line) + projection;
}

}  // namespace lp::cli
