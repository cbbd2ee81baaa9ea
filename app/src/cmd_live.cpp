// Live light probe from a V4L2 camera: live (the replay pipeline with a camera as its source)
// and devices (what each camera offers).
#include <linux/videodev2.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <tuple>

#include "commands.h"
#include "liveprobe/capture/v4l2.h"
#include "liveprobe/sh/error.h"
#include "progress.h"
#include "scene.h"

namespace lp::cli {

const CommandSpec kLiveSpec{
    "live",
    "DEVICE",
    "A live light probe: streams a V4L2 camera (a 360 camera over UVC, or a webcam looking at a\n"
    "chrome ball with --layout mirrorball --circle cx,cy,r), re-projects the nine coefficients "
    "every\n"
    "frame and lights the model with them. Capture runs on its own thread and is never held back\n"
    "by drawing. --record saves the stream as it runs, for replay.",
    [] {
      std::vector<OptionSpec> o;
      for (const auto& opt : streamOptions())
        if (opt.name != "--fps") o.push_back(opt);  // --fps is the camera's here
      const std::string g = "Camera";
      o.insert(o.end(),
               {{"--format", "mjpeg|yuyv|nv12|rgb24|auto",
                 "pixel format (default auto: MJPEG first)", false, false, g},
                {"--size", "WxH", "capture size asked of the camera (default: its largest)", false,
                 false, g},
                {"--fps", "N", "frame rate asked of the camera, up to 1000", false, false, g},
                {"--lock-exposure", "SECONDS",
                 "let auto exposure settle (default 2 s), then lock exposure, gain, white balance",
                 false, true, g},
                {"--mjpeg-reduce", "1|2|4|8", "decode MJPEG at a reduced scale (default 1)", false,
                 false, g},
                {"--timeout", "SECONDS", "stop when no frame arrives for this long (default 2)",
                 false, false, g},
                {"--record", "FILE",
                 "save the camera stream (.mkv FFV1, .avi MJPEG, .mp4 H.264) while it runs", false,
                 false, g},
                {"--view-size", "WxH", "window or frame size (default 1280x720; headless 640x360)",
                 false, false, "Output"}});
      auto scene = sceneOptions();
      o.insert(o.end(), scene.begin(), scene.end());
      return o;
    }(),
    1,
    1,
    "a V4L2 video-capture node, e.g. /dev/video0"};

int runLive(const Args& a) {
  layoutFromArgs(a);
  CameraSettings cs;
  cs.device = a.positional()[0];
  try {
    cs.format = parseCameraFormat(a.get("--format", "auto"));
  } catch (const Error& e) {
    throw Error("--format: " + std::string(e.what()));
  }
  if (a.has("--size")) std::tie(cs.width, cs.height) = parseSize(a.get("--size"), "--size");
  cs.fps = a.number("--fps", 0.0);
  if (cs.fps < 0 || cs.fps > 1000)
    throw Error("--fps " + a.get("--fps") + ": expected a rate up to 1000");
  cs.mjpegReduce = a.integer("--mjpeg-reduce", 1);
  if (cs.mjpegReduce != 1 && cs.mjpegReduce != 2 && cs.mjpegReduce != 4 && cs.mjpegReduce != 8)
    throw Error("--mjpeg-reduce " + a.get("--mjpeg-reduce") + ": expected 1, 2, 4 or 8");
  cs.timeoutMs = int(1000 * a.number("--timeout", 2.0));
  if (cs.timeoutMs < 10) throw Error("--timeout " + a.get("--timeout") + ": too short");
  auto camera = std::make_unique<V4l2Source>(cs);
  camera->start();
  const bool headless =
      a.has("--headless") || !(std::getenv("DISPLAY") || std::getenv("WAYLAND_DISPLAY"));
  std::fprintf(
      stderr, "liveprobe live: %s%s\n", camera->describe().c_str(),
      headless && !a.has("--frames") && !a.has("--duration") ? "; running until Ctrl-C" : "");
  if (a.has("--lock-exposure")) {
    const double settle = a.get("--lock-exposure").empty() ? 2.0 : a.number("--lock-exposure", 2.0);
    const LockedExposure l = camera->lockExposure(settle);
    auto show = [](const std::optional<std::int32_t>& v) {
      return v ? std::to_string(*v) : std::string("n/a");
    };
    std::fprintf(
        stderr,
        "liveprobe live: locked after %.1f s: exposure %s x 100 us, gain %s, white balance %s K\n",
        settle, show(l.exposure100us).c_str(), show(l.gain).c_str(), show(l.whiteBalanceK).c_str());
  }
  return runStreamForLive(a, std::move(camera));
}

const CommandSpec kDevicesSpec{
    "devices",
    "[DEVICE...]",
    "Lists V4L2 cameras (default: every /dev/video*) with their formats, sizes, frame rates and\n"
    "controls. Only video-capture nodes are cameras: a UVC camera's metadata node is skipped.",
    {},
    0,
    64,
    "V4L2 nodes to list (default: every /dev/video*)"};

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

}  // namespace lp::cli
