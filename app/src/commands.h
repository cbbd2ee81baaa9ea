#pragma once
// The subcommands of the liveprobe program. Each returns the process exit code; errors are
// thrown as lp::Error and printed by main() as one line.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "args.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/hdr/merge.h"
#include "liveprobe/sh/lights.h"
#include "settings.h"

namespace lp::cli {

struct Command {
  CommandSpec spec;
  int (*run)(const Args&);
  const char* brief;  ///< one line for `liveprobe --help`
};

const std::vector<Command>& commands();

/// The optional parts of a build (CMake's LIVEPROBE_WITH_*, liveprobe/backends.h).
enum class OptionalBackend : std::uint8_t { Window, V4l2, Stream, Mqtt, Network };
/// Whether this build has it.
bool builtIn(OptionalBackend b);
/// The GL contexts this build can open, for --version: "window (GLFW), EGL headless (devices:
/// 0 software), OSMesa headless (CPU)".
std::string glLine();
/// Throws lp::Error "WHAT: this liveprobe was built without NAME (ITS CMAKE OPTION); INSTEAD"
/// unless it is built in (an empty `what` for a whole command, which main() names).
void requireBackend(OptionalBackend b, const std::string& what, const std::string& instead = {});
/// For --version: "window (GLFW), V4L2 cameras, WebSocket stream, MQTT", then "; built without
/// ..." the ones this build lacks.
std::string backendsLine();

int runCoeffs(const Args&);
int runIrradiance(const Args&);
int runCompare(const Args&);
int runRender(const Args&);
int runView(const Args&);
int runReplay(const Args&);
int runRecord(const Args&);
int runBench(const Args&);
int runLive(const Args&);
int runDevices(const Args&);
int runCalibrate(const Args&);
int runCalibrateLens(const Args&);
/// The replay pipeline with an opened camera as its source (cmd_replay.cpp).
int runStreamForLive(const Args& a, std::unique_ptr<FrameSource> camera);
std::vector<OptionSpec> streamOptions();
/// What goes together among them: --serve-* with --serve, --mqtt-* with --publish, --hud.
void checkStreamOptions(const Settings& s);
/// The camera response --response FILE or --gamma G names; none when neither is given.
std::optional<CameraResponse> responseOption(const StreamSettings& st);
// Options more than one command takes, each declared once here with its one help text (a
// command adds them to its list, under its own help section `group`).
/// --sun and --lights K: extraction of the dominant compact lights (liveprobe/sh/lights.h).
std::vector<OptionSpec> lightOptionSpecs(const std::string& group = {});
/// --threads N: threads for one frame's projection.
OptionSpec threadsOption(const std::string& group = {});
/// --quiet: no progress line.
OptionSpec quietOption(const std::string& group = {});
/// --hud (into headless output) and, where there can be a window, --no-hud.
std::vector<OptionSpec> hudOptions(const std::string& group, bool window);
/// A coefficient format (exchange/engine_export.h: parseCoeffFormat), parsed as the line is
/// read; `streaming`: the formats a stream's records take (no glsl, no text, no gltf).
template <class F>
OptionSpec coeffFormatOption(const std::string& name, const std::string& help, bool streaming,
                             F field, const std::string& group = {}) {
  OptionSpec o = declared(name, "FORMAT", help, group);
  o.set = [name, streaming, field](Settings& s, const std::string& v) {
    field(s) = parseCoeffFormat(v, name, streaming);
  };
  return o;
}

/// Options several commands take with a help, range and default of their own: each is declared
/// here once (its name, value, parser and the one field it sets), and a command gives the rest.
namespace opt {
/// --size WxH (output.size): what the command makes, draws, or asks of a camera; each side 1 to
/// `maxSide`.
OptionSpec size(const std::string& help, int maxSide, const std::string& dflt,
                const std::string& group = {});
/// --out FILE (output.out), its extension one of `extensions`.
OptionSpec out(const std::string& value, const std::string& help,
               const std::vector<std::string>& extensions, const std::string& group = {});
/// --frames N (output.frames), 1 to `most`.
OptionSpec frames(const std::string& help, std::int64_t most, const std::string& dflt,
                  const std::string& group = {});
/// --fps F (stream.fps): a frame rate in `range`.
OptionSpec fps(const std::string& help, Range range, const std::string& dflt,
               const std::string& group = {});
/// --duration SECONDS (output.duration).
OptionSpec duration(const std::string& help, const std::string& group = {});
/// --format (output.format): the form a command prints, a coefficient format
/// (liveprobe/exchange/engine_export.h), one of `names` where given; `dflt` is the command's
/// when none is given.
OptionSpec format(const std::string& help, const std::vector<std::string>& names,
                  const std::string& dflt, const std::string& group = {});
}  // namespace opt

/// Refuses --hud with --no-hud (one line).
void checkHudOptions(const Settings& s);
/// The extraction asked for: maxLights = K with --lights K, 1 with --sun alone, 0 without either.
LightOptions chooseLights(const Settings& s);

/// Run-time data beside the program: <the executable's folder>/../share/liveprobe, in the build
/// tree as in an install (the build stages it there).
std::string shareDir();
/// $LIVEPROBE_DEFAULT_RECORDING, or the bundled recordings/sky.mkv in shareDir().
std::string defaultRecording();

extern const CommandSpec kCoeffsSpec, kIrradianceSpec, kCompareSpec, kRenderSpec, kViewSpec,
    kReplaySpec, kRecordSpec, kBenchSpec, kLiveSpec, kDevicesSpec, kCalibrateSpec,
    kCalibrateLensSpec;

}  // namespace lp::cli
