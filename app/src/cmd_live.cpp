// Live light probe from a V4L2 camera: live (the replay pipeline with a camera as its source)
// and devices (what each camera offers).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>
#include <tuple>

#include "commands.h"
#include "environment.h"
#include "liveprobe/backends.h"
#include "liveprobe/capture/atomic_file.h"
#include "liveprobe/capture/network.h"
#include "liveprobe/capture/recorder.h"
#include "liveprobe/capture/v4l2.h"
#include "liveprobe/hdr/bracketing.h"
#include "liveprobe/hdr/calibrate.h"
#include "liveprobe/hdr/merge.h"
#include "liveprobe/sh/error.h"
#include "progress.h"
#include "scene.h"

namespace lp::cli {

namespace {

const std::string kCameraGroup = "Camera";

/// What every command that opens a camera takes.
std::vector<OptionSpec> cameraOptions() {
  const std::string g = kCameraGroup;
  OptionSpec lock{
      "--lock-exposure",
      "SECONDS",
      "let auto exposure settle for SECONDS (0 to 3600, default 2), then lock exposure, "
      "gain, white balance",
      false,
      true,
      g};
  lock.set = [](Settings& s, const std::string& v) {
    s.live.lockExposure = v.empty() ? 2.0 : parseNumberIn("--lock-exposure", v, {0, 3600});
  };
  return {choiceOption("--pixel-format",
                       "pixel format (auto: MJPEG first, H.264 and HEVC only when nothing else)",
                       {"mjpeg", "yuyv", "nv12", "rgb24", "h264", "hevc", "auto"}, "auto",
                       LP_FIELD(camera.format), g,
                       [](const std::string& v) { return parseCameraFormat(v); }),
          opt::size("capture size asked of the camera", 16384, "its largest", g),
          opt::fps("frame rate asked of the camera", {0, 1000}, "0: its own", g),
          lock,
          choiceOption("--mjpeg-reduce", "decode MJPEG at a reduced scale", {"1", "2", "4", "8"},
                       "1", LP_FIELD(camera.mjpegReduce), g,
                       [](const std::string& v) { return std::stoi(v); }),
          [&] {  // capture's field, in ms
            const Range r{0.01, 3600};
            OptionSpec o = declared(
                "--timeout", "SECONDS",
                withRange("stop when no frame arrives for this long", rangeText(r), "2"), g);
            o.set = [r](Settings& s, const std::string& v) {
              s.camera.timeoutMs = int(std::lround(1000 * parseNumberIn("--timeout", v, r)));
            };
            return o;
          }(),
          textOption("--metadata", "DEVICE",
                     "the camera's UVC metadata node, which says each frame's exposure (default: "
                     "the node after DEVICE, as uvcvideo numbers them)",
                     LP_FIELD(live.metadata), g)};
}

#if LIVEPROBE_WITH_V4L2
CameraSettings cameraSettingsFrom(const std::string& device, const Settings& s) {
  CameraSettings cs = s.camera;
  cs.device = device;
  if (s.output.size) std::tie(cs.width, cs.height) = *s.output.size;
  cs.fps = s.stream.fps.value_or(0.0);
  return cs;
}

/// Settles auto exposure for --lock-exposure's seconds (default 2), locks, and says what it locked.
LockedExposure lockExposure(const LiveSettings& c, V4l2Source& camera, const char* command) {
  const double settle = c.lockExposure.value_or(2.0);
  const LockedExposure l = camera.lockExposure(settle);
  auto show = [](const std::optional<std::int32_t>& v) {
    return v ? std::to_string(*v) : std::string("n/a");
  };
  std::fprintf(stderr,
               "liveprobe %s: locked after %.1f s: exposure %s x 100 us, gain %s, white "
               "balance %s K\n",
               command, settle, show(l.exposure100us).c_str(), show(l.gain).c_str(),
               show(l.whiteBalanceK).c_str());
  return l;
}

#endif  // LIVEPROBE_WITH_V4L2

/// --bracket EV,EV,...: 2 to 5 distinct stops in [-20, 20].
std::vector<double> bracketStops(const std::string& text) {
  std::vector<double> stops;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    const double ev = parseNumber(item, "--bracket");
    if (!(ev >= -20 && ev <= 20))
      throw Error("--bracket " + text + ": " + item + " is not a stop in -20..20");
    if (std::find(stops.begin(), stops.end(), ev) != stops.end())
      throw Error("--bracket " + text + ": " + item + " is given twice");
    stops.push_back(ev);
  }
  if (stops.size() < 2 || stops.size() > std::size_t(kMaxBracket))
    throw Error("--bracket " + text + ": expected 2 to " + std::to_string(kMaxBracket) +
                " stops, e.g. -12,-6,0");
  return stops;
}

#if LIVEPROBE_WITH_V4L2
/// The camera, bracketing: the anchor taken, the first exposure asked, the plan said.
std::unique_ptr<FrameSource> startBracket(std::unique_ptr<V4l2Source> camera,
                                          const std::string& device,
                                          const std::vector<double>& stops, std::int32_t locked,
                                          const CameraResponse& response) {
  V4l2Source& control = *camera;
  const bool reports = camera->reportsExposure();
  auto bracketed = std::make_unique<BracketedCamera>(
      std::move(camera), control,
      BracketOptions{stops, locked, response, device, [](const std::string& w) { warn(w); }});
  const std::vector<std::int32_t>& asked = bracketed->bracketing().asked();
  // Each stop as the control gives it: its whole units (100 us) round a short exposure; its
  // range clamps the ends.
  std::string plan, moved;
  for (std::size_t i = 0; i < stops.size(); ++i) {
    plan += (i ? ", " : "") + formatNumber(stops[i]) + " EV " + std::to_string(asked[i]);
    const double want = locked * std::exp2(stops[i]);
    const double actual = std::log2(double(asked[i]) / locked);
    if (std::abs(actual - stops[i]) > 0.1)
      moved += "; " + formatNumber(stops[i]) + " EV is " + formatNumber(actual, 3) + " EV, " +
               (std::abs(double(asked[i]) - want) <= 0.5 ? "the nearest whole 100 us"
                                                         : "the control's limit");
  }
  std::fprintf(stderr, "liveprobe live: bracket %s (x 100 us)%s; %s\n", plan.c_str(), moved.c_str(),
               reports ? "each frame's exposure from the camera's metadata"
                       : ("each frame's exposure measured from its pixels (" + response.name +
                          " response; the camera sends no per-frame exposure times)")
                             .c_str());
  bracketed->start();
  return bracketed;
}

#endif  // LIVEPROBE_WITH_V4L2

}  // namespace

const CommandSpec kLiveSpec{
    "live",
    "DEVICE|URL",
    "A live light probe: streams a V4L2 camera (a 360 camera over UVC, or a webcam looking at a\n"
    "chrome ball with --layout mirrorball --circle cx,cy,r) or a camera on the network (rtsp://,\n"
    "http://, srt://, udp://), re-projects the nine coefficients every frame and lights the model\n"
    "with them. Capture runs on its own thread and is never held back\n"
    "by drawing. --record saves the stream as it runs, for replay. --bracket makes HDR from an\n"
    "8-bit camera (docs/hdr.md).",
    [] {
      std::vector<OptionSpec> o;
      for (const auto& opt : streamOptions())
        if (opt.name != "--fps") o.push_back(opt);  // --fps is the camera's here
      const auto camera = cameraOptions();
      o.insert(o.end(), camera.begin(), camera.end());
      const std::string g = kCameraGroup;
      OptionSpec bracket{"--bracket",
                         "EV,EV,...",
                         "HDR from an 8-bit camera: cycle 2 to 5 exposures, in stops from the "
                         "locked one (e.g. -12,-6,0), and merge the newest of each into radiance "
                         "every frame",
                         false,
                         false,
                         g};
      bracket.set = [](Settings& s, const std::string& v) { s.live.bracket = bracketStops(v); };
      OptionSpec reconnect = declared(
          "--reconnect", "SECONDS",
          withRange("a network stream that ends or stalls past --timeout is opened again, "
                    "waiting 0.25 s, then twice as long each try, up to SECONDS between tries "
                    "(0: the run ends instead)",
                    rangeText({0, 3600}), "10"),
          g);
      reconnect.set = [](Settings& s, const std::string& v) {
        s.live.reconnect = parseNumberIn("--reconnect", v, {0, 3600});
      };
      o.insert(
          o.end(),
          {bracket, reconnect,
           choiceOption("--rtsp-transport", "how an rtsp:// stream is carried", {"tcp", "udp"},
                        "tcp", LP_FIELD(live.rtspTransport), g),
           fileOption("--record", "FILE",
                      "save the camera stream while it runs: .mkv (FFV1), .avi (MJPEG), "
                      ".mp4 (H.264), or frames: %04d.png (the codes), %04d.exr (radiance); "
                      "a bracket: .mkv or .png frames",
                      {".mkv", ".avi", ".mp4", ".exr", ".hdr", ".png"}, LP_FIELD(stream.record), g),
           sizeOption("--view-size", "window or frame size", 16384, "1280x720; headless 640x360",
                      LP_FIELD(live.viewSize), "Output")});
      auto scene = sceneOptions();
      o.insert(o.end(), scene.begin(), scene.end());
      return o;
    }(),
    1,
    1,
    "a V4L2 video-capture node, e.g. /dev/video0, or a network stream's URL (rtsp://, "
    "http(s)://, srt://, udp://, rtp://, tcp://)",
    [](const Settings& s) {
      checkStreamOptions(s);
      if (s.live.metadata && s.live.bracket.empty()) throw Error("--metadata goes with --bracket");
      if (!s.live.bracket.empty() && s.stream.record) try {
          checkBracketRecording(*s.stream.record);
        } catch (const Error& e) {
          throw Error(std::string("--record ") + e.what());
        }
    }};

namespace {
int runCameraLive(const Args& a);

#if LIVEPROBE_WITH_NETWORK
/// live URL: a camera on the network, read through FFmpeg, reconnecting.
int runNetworkLive(const Args& a, const std::string& url) {
  const Settings& s = a.settings();
  // What only a V4L2 camera is asked: a network camera sends what it was set up to send.
  auto refuse = [&](bool given, const char* option, const char* what) {
    if (given)
      throw Error(std::string(option) + " " + what + ", which " + redactUrl(url) +
                  " (a network stream) has not: set its camera up on the camera itself");
  };
  refuse(!s.live.bracket.empty(), "--bracket", "needs a V4L2 camera's exposure control");
  refuse(s.live.lockExposure.has_value(), "--lock-exposure",
         "needs a V4L2 camera's exposure control");
  refuse(s.live.metadata.has_value(), "--metadata", "needs a V4L2 camera's metadata node");
  refuse(s.camera.format != CameraFormat::Auto, "--pixel-format", "asks a V4L2 camera");
  refuse(s.output.size.has_value(), "--size", "asks a V4L2 camera");
  refuse(s.stream.fps.has_value(), "--fps", "asks a V4L2 camera");
  NetworkSettings n;
  n.url = url;
  n.timeoutMs = s.camera.timeoutMs;
  n.reconnectSeconds = s.live.reconnect;
  n.rtspUdp = s.live.rtspTransport == "udp";
  n.mjpegReduce = s.camera.mjpegReduce;
  n.say = [](const std::string& line) {
    std::fprintf(stderr, "liveprobe live: %s\n", line.c_str());
  };
  n.interrupted = stopRequested;
  installStopHandlers();  // a Ctrl-C while connecting ends the wait
  auto source = openNetwork(std::move(n));
  std::fprintf(stderr, "liveprobe live: %s%s\n", source->describe().c_str(),
               s.output.frames || s.output.duration ? "" : "; running until Ctrl-C");
  return runStreamForLive(a, std::move(source));
}
#endif
}  // namespace

int runLive(const Args& a) {
  const Settings& s = a.settings();
  layoutSpec(s.panorama, nullptr, true);
  const std::string& name = a.positional()[0];
  if (isNetworkUrl(name)) {
    requireBackend(OptionalBackend::Network, redactUrl(name));
#if LIVEPROBE_WITH_NETWORK
    return runNetworkLive(a, name);
#endif
  }
  return runCameraLive(a);
}

namespace {
#if LIVEPROBE_WITH_V4L2
int runCameraLive(const Args& a) {
  const Settings& s = a.settings();
  CameraSettings cs = cameraSettingsFrom(a.positional()[0], s);
  const std::vector<double>& stops = s.live.bracket;
  if (!stops.empty()) cs.metadataDevice = s.live.metadata.value_or(siblingMetadataNode(cs.device));
  auto camera = startCamera(cs, s.live.metadata.has_value());
  std::fprintf(stderr, "liveprobe live: %s%s\n", camera->describe().c_str(),
               s.output.frames || s.output.duration ? "" : "; running until Ctrl-C");
  // Bracketing counts its stops from a locked exposure.
  LockedExposure locked;
  if (s.live.lockExposure || !stops.empty()) locked = lockExposure(s.live, *camera, "live");
  if (!stops.empty())
    return runStreamForLive(
        a, startBracket(std::move(camera), cs.device, stops, locked.exposure100us.value_or(1),
                        responseOption(s.stream).value_or(CameraResponse::srgb())));
  return runStreamForLive(a, std::move(camera));
}
#else
int runCameraLive(const Args&) {
  requireBackend(OptionalBackend::V4l2, "");
  return 1;
}
#endif
}  // namespace

namespace {
/// --stops LO,HI: whole stops from the locked exposure, -20 <= LO < HI <= 20.
OptionSpec stopsOption() {
  OptionSpec o{
      "--stops",
      "LO,HI",
      "the sweep, in whole stops from the locked exposure (default -6,3); it goes on below LO "
      "while the shortest frame reads no code of 4 or less, up to 12 stops more",
      false,
      false,
      kCameraGroup};
  o.set = [](Settings& s, const std::string& v) {
    const auto r = parseNumberList(v, "--stops", 2, "LO,HI");
    if (!(r[0] < r[1]) || r[0] < -20 || r[1] > 20)
      throw Error("--stops " + v + ": expected LO,HI with -20 <= LO < HI <= 20");
    s.live.stops = {r[0], r[1]};
  };
  return o;
}
}  // namespace

const CommandSpec kCalibrateSpec{
    "calibrate",
    "DEVICE",
    "Recovers a camera's response curve (code value to linear light) for --response: locks the\n"
    "exposure, sweeps it over a static scene in whole stops (below LO until the darkest codes are\n"
    "read), and solves for the curve from the codes each pixel took in each pair of exposures.\n"
    "The curve must rise with the code; codes no frame read get no weight in a merge. Point the\n"
    "camera at a still scene with both shadows and highlights, and keep it still.",
    [] {
      auto o = cameraOptions();
      o.insert(
          o.end(),
          {opt::out("FILE.json", "where the response goes (required)", {".json"}, "Output"),
           stopsOption(),
           integerOption("--settle", "N",
                         "frames to let pass after each change before one is kept; a camera "
                         "whose metadata reports exposures keeps the first that shows the new one",
                         1, 60, "8", LP_FIELD(live.settle), kCameraGroup)});
      return o;
    }(),
    1,
    1,
    "a V4L2 video-capture node, e.g. /dev/video0",
    [](const Settings& s) {
      if (!s.output.out) throw Error("--out FILE.json is required");
    }};

#if LIVEPROBE_WITH_V4L2
int runCalibrate(const Args& a) {
  const Settings& s = a.settings();
  CameraSettings cs = cameraSettingsFrom(a.positional()[0], s);
  const auto& range = s.live.stops;
  const int settle = s.live.settle;
  // The metadata node when there is one (frames then say their exposure); the settle otherwise.
  cs.metadataDevice = s.live.metadata.value_or(siblingMetadataNode(cs.device));
  auto camera = startCamera(cs, s.live.metadata.has_value());
  std::fprintf(stderr, "liveprobe calibrate: %s%s\n", camera->describe().c_str(),
               camera->reportsExposure() ? "; frames report their exposure" : "");
  const LockedExposure locked = lockExposure(s.live, *camera, "calibrate");
  if (!locked.exposure100us)
    throw Error(cs.device + ": the camera has no exposure time control " +
                "(V4L2_CID_EXPOSURE_ABSOLUTE): it cannot be calibrated");
  SweepOptions sweepOptions{
      .lowest = int(std::ceil(range[0])),
      .highest = int(std::floor(range[1])),
      .locked = *locked.exposure100us,
      .settle = settle,
      .name = cs.device,
      .stopRequested = stopRequested,
      .onStop = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); }};
  const Sweep sweep = sweepExposures(*camera, *camera, sweepOptions);
  if (sweep.stopped) {
    std::fprintf(stderr, "liveprobe calibrate: stopped by a signal; nothing written\n");
    return exitStatusFor(stopSignal());
  }
  // A pixel's colour is its own only through RGB24: YUYV shares it between two pixels, NV12 and
  // (most) MJPEG among four, and the response is read from pixels whose block reads one colour.
  const std::string format = fourccText(camera->fourcc());
  CameraResponse r = calibrateResponse(sweep.frames, format == "YUYV"   ? ChromaBlock{2, 1}
                                                     : format == "RGB3" ? ChromaBlock{1, 1}
                                                                        : ChromaBlock{2, 2});
  r.controlDelay = sweep.controlDelay;
  if (format != "RGB3")
    std::fprintf(stderr,
                 "warning: %s sends %s, which %s: the response holds within 3%% from code %d up "
                 "(below, the format's own steps are more than 3%% of the light); calibrate "
                 "through RGB24 (--pixel-format rgb24) where the camera offers it\n",
                 cs.device.c_str(), format == "MJPG" ? "MJPEG" : format.c_str(),
                 format == "MJPG" ? "compresses each pixel's colour with its neighbours'"
                                  : "shares each pixel's colour with its neighbours'",
                 kYuvTrustedFrom);
  AtomicTextFile out(*s.output.out);
  out.line(r.json());
  out.commit();
  const PowerLaw like = fitPowerLaw([&](int i) { return r.linear[1][std::size_t(i)]; });
  std::string unread;
  if (r.readFrom > kDarkestCode)
    unread += "; codes below " + std::to_string(r.readFrom) + " were never read";
  if (r.readTo < kBrightestCode)
    unread += std::string(unread.empty() ? "; codes" : " nor") + " above " +
              std::to_string(r.readTo) + (unread.empty() ? " were never read" : "");
  if (!unread.empty()) unread += " (a merge counts them as noise or clipped)";
  const std::string delayText =
      r.controlDelay ? "a new exposure shows " + std::to_string(*r.controlDelay) +
                           (*r.controlDelay == 1 ? " frame" : " frames") + " after it is asked"
                     : "no stop showed when a new exposure takes effect";
  std::fprintf(stderr,
               "liveprobe calibrate: %zu exposures; the response rises with the code (green is "
               "like a gamma of %.2f over codes 32-240); codes %d-%d read%s; %s; written to %s\n",
               sweep.frames.size(), like.gamma, r.readFrom, r.readTo, unread.c_str(),
               delayText.c_str(), s.output.out->c_str());
  return 0;
}
#else
int runCalibrate(const Args&) {
  requireBackend(OptionalBackend::V4l2, "");
  return 1;
}
#endif

const CommandSpec kDevicesSpec{
    "devices",
    "[DEVICE...]",
    "Lists V4L2 cameras (default: every /dev/video*) with their formats, sizes, frame rates and\n"
    "controls. Only video-capture nodes are cameras: a UVC camera's metadata node is skipped.",
    {},
    0,
    64,
    "V4L2 nodes to list (default: every /dev/video*)"};

#if LIVEPROBE_WITH_V4L2
int runDevices(const Args& a) {
  std::vector<std::string> paths = a.positional();
  if (paths.empty()) {
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator("/dev", ec))
      if (e.path().filename().string().rfind("video", 0) == 0) paths.push_back(e.path().string());
    std::sort(paths.begin(), paths.end());
    if (paths.empty()) {
      std::cout << "no cameras (no /dev/video* on this machine)\n";
      return 0;
    }
  }
  int failures = 0;
  for (const auto& p : paths) {
    CameraInfo info;
    try {
      info = queryCamera(p);
    } catch (const Error& e) {
      errs() << "liveprobe devices: " << e.what() << "\n";
      ++failures;
      continue;
    }
    if (!info.videoCapture) {  // a UVC camera's metadata node, an output device, ...
      if (!a.positional().empty())
        errs() << "liveprobe: " << p << ": " << info.card << ": a " << info.kind
               << " node, not a camera; skipped\n";
      continue;
    }
    std::cout << p << ": " << info.card << " (" << info.driver << ", " << info.bus << ")\n";
    for (const auto& m : info.modes) {
      std::cout << "  " << fourccText(m.fourcc) << " " << m.width << "x" << m.height << " @";
      for (double f : m.fps) std::cout << " " << f;
      std::cout << " fps\n";
    }
    for (const auto& c : info.controls)
      std::cout << "  control " << c.name << " = " << c.value << " [" << c.minimum << ".."
                << c.maximum << ", default " << c.defaultValue << "]\n";
  }
  return failures ? 1 : 0;
}
#else
int runDevices(const Args&) {
  requireBackend(OptionalBackend::V4l2, "");
  return 1;
}
#endif

}  // namespace lp::cli
