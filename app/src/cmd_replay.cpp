// Dynamic lighting from streams: replay (a recording, video, sequence or the synthetic sky,
// re-projected every frame, drawing a model) and record (save a source for replay).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <mutex>

#include "commands.h"
#include "dynamic_resolution.h"
#include "environment.h"
#include "gpu_projection.h"
#include "hud.h"
#include "liveprobe/capture/lens.h"
#include "liveprobe/capture/open_source.h"
#include "liveprobe/capture/pipeline.h"
#include "liveprobe/capture/recorder.h"
#include "liveprobe/hdr/bracketed_source.h"
#include "liveprobe/sh/error.h"
#include "progress.h"
#include "scene.h"
#include "scene_gl.h"
#include "stream_outputs.h"
#include "stream_sinks.h"
#include "stream_summary.h"
#include "viewer.h"

namespace lp::cli {

namespace fs = std::filesystem;

std::string shareDir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return (exe.parent_path().parent_path() / "share" / "liveprobe").string();
}

std::string defaultRecording() {
  if (const char* e = std::getenv("LIVEPROBE_DEFAULT_RECORDING")) return e;
  return shareDir() + "/recordings/sky.mkv";
}

namespace {

Photometry photometryFrom(const StreamSettings& st) {
  Photometry p;
  if (st.gamma) p.gamma = float(*st.gamma);
  p.exposure = float(st.inputExposure);
  return p;
}

}  // namespace

std::vector<OptionSpec> streamOptions() {
  auto o = layoutOptions();
  const std::string g = "Stream";
  OptionSpec gamma{
      "--gamma",
      "srgb|G",
      "8-bit decoding, a bracket's merge included: the sRGB curve (default) or code^G, G "
      "above 0.2 and below 5",
      false,
      false,
      g};
  gamma.set = [](Settings& s, const std::string& v) {
    if (v == "srgb") return s.stream.gamma.reset();
    const double x = parseNumber(v, "--gamma");
    if (!(x > 0.2 && x < 5.0))
      throw Error("--gamma " + v + ": expected srgb or a gamma in (0.2, 5)");
    s.stream.gamma = x;
  };
  o.insert(
      o.end(),
      {gamma,
       numberOption("--input-exposure", "X", "linear radiance scale applied to the input",
                    {0, 1e6, true}, "1", LP_FIELD(stream.inputExposure), g),
       numberOption("--smooth", "SECONDS",
                    "exponential moving average of the coefficients and lights (and its latency)",
                    {0, 3600}, "0", LP_FIELD(stream.smooth), g),
       opt::fps("frame rate of image sequences and stills", {0, 1000, true}, "30", g),
       integerOption("--reduce", "F",
                     "equirect: project an F x F area average (its error: docs/accuracy.md)", 1, 64,
                     "1", LP_FIELD(stream.reduce), g),
       threadsOption(g),
       opt::frames("stop after N frames", 1000000000, "", g),
       opt::duration("stop after this much of the source's time", g),
       textOption("--coeffs-out", "FILE.jsonl",
                  "one JSON line per frame: coefficients and stage timings",
                  LP_FIELD(output.coeffsOut), g),
       coeffFormatOption("--coeffs-format",
                         "the coefficients in --coeffs-out lines: json (default), three, babylon, "
                         "filament, unity or webxr (docs/engines.md)",
                         true, LP_FIELD(output.coeffsFormat), g),
       textOption("--serve", "[ADDR:]PORT",
                  "serve every frame's record over WebSocket "
                  "(ws://ADDR:PORT/?format=three|babylon|...) and a three.js page lit by it at "
                  "http://ADDR:PORT/; ADDR defaults to 127.0.0.1",
                  LP_FIELD(stream.serve), g),
       flagOption("--serve-remote", "allow --serve on an address other machines can reach",
                  LP_FIELD(stream.serveRemote), g),
       integerOption("--serve-clients", "N", "--serve: at most N clients at once", 1, 1000, "32",
                     LP_FIELD(stream.serveClients), g),
       integerOption("--serve-idle", "SECONDS",
                     "--serve: close a client that answers no ping for this long", 2, 3600, "30",
                     LP_FIELD(stream.serveIdle), g),
       textOption("--publish", "mqtt[s]://[USER@]HOST[:PORT]/TOPIC",
                  "publish every frame's record to an MQTT broker, retained (in --coeffs-format); "
                  "the password from USER:PASSWORD@, LIVEPROBE_MQTT_PASSWORD or "
                  "--mqtt-password-file; mqtts:// checks the broker against the system's CAs",
                  LP_FIELD(stream.publish), g),
       textOption("--mqtt-cafile", "FILE",
                  "mqtts://: trust the CAs in FILE (PEM) instead of the system's",
                  LP_FIELD(stream.mqttCafile), g),
       textOption("--mqtt-password-file", "FILE", "the MQTT user's password, the file's first line",
                  LP_FIELD(stream.mqttPasswordFile), g),
       textOption("--response", "FILE",
                  "8-bit frames: the camera's response, from `liveprobe calibrate` (default: "
                  "sRGB); a bracketed recording's own response otherwise",
                  LP_FIELD(stream.response), g),
       numberOption("--hold-below", "C",
                    "keep the last good lighting while a frame's confidence is below C (a hand "
                    "over the lens, a flash)",
                    {0, 1}, "", LP_FIELD(stream.holdBelow), g),
       quietOption(g)});
  for (auto& shared : {lightOptionSpecs(g), hudOptions(g, true)})
    o.insert(o.end(), shared.begin(), shared.end());
  return o;
}

std::optional<CameraResponse> responseOption(const StreamSettings& st) {
  if (st.response) return CameraResponse::load(*st.response);
  if (st.gamma) return CameraResponse::gamma(float(*st.gamma));
  return std::nullopt;
}

void checkStreamOptions(const Settings& s) {
  checkHudOptions(s);
  const StreamSettings& st = s.stream;
  if (!st.serve && (st.serveRemote || st.serveClients || st.serveIdle))
    throw Error("--serve-remote, --serve-clients and --serve-idle go with --serve");
  if (!st.publish && (st.mqttCafile || st.mqttPasswordFile))
    throw Error("--mqtt-cafile and --mqtt-password-file go with --publish");
  if (st.response && st.gamma)
    throw Error("--response and --gamma: give one of them (a response replaces the curve)");
}

const CommandSpec kReplaySpec{
    "replay",
    "[SOURCE]",
    "Replays a panoramic stream, re-projecting the nine coefficients every frame, and draws the\n"
    "model lit by them with the frame behind it. SOURCE: a video (mp4, webm, mkv, avi, mov), an\n"
    "image sequence (folder or %04d-style pattern), an image, a folder of six cube faces, or\n"
    "synthetic[:WxH[@FPS]]; default: the bundled recording recordings/sky.mkv.\n"
    "In a window capture runs in real time on its own thread and the newest coefficients are\n"
    "drawn (stale frames are dropped and counted); Space pauses, Right steps, F1 lists the keys.\n"
    "Headless (--headless, or no display) every frame is drawn, and written with --out-dir or\n"
    "--out-video. Ctrl-C stops cleanly: outputs are finalised, the summary printed, exit 130.",
    [] {
      auto o = streamOptions();
      const std::string g = "Output";
      o.insert(
          o.end(),
          {flagOption("--loop", "start again at the end of the source", LP_FIELD(stream.loop),
                      "Stream"),
           flagOption("--realtime",
                      "headless: play at the source's frame rate, not as fast as frames render "
                      "(the default with --serve or --publish)",
                      LP_FIELD(stream.realtime), "Stream"),
           opt::size("window or frame size", 16384, "1280x720; headless 640x360", g),
           textOption("--out-dir", "DIR",
                      "headless: write each rendered frame as DIR/frame_NNNNNN.png",
                      LP_FIELD(output.outDir), g),
           fileOption("--out-video", "FILE",
                      "headless: write the rendered frames as a video (.mkv FFV1, .avi MJPEG, "
                      ".mp4 H.264)",
                      {".mkv", ".avi", ".mp4"}, LP_FIELD(output.outVideo), g)});
      auto scene = sceneOptions();
      o.insert(o.end(), scene.begin(), scene.end());
      return o;
    }(),
    0,
    1,
    LP_SOURCE_KINDS "; default: the bundled recording recordings/sky.mkv",
    [](const Settings& s) {
      checkStreamOptions(s);
      const OutputSettings& o = s.output;
      if (o.outDir && o.outVideo) throw Error("give --out-dir or --out-video, not both");
      if ((o.outDir || o.outVideo) && s.stream.loop && !o.frames && !o.duration)
        throw Error("--loop with --out-dir or --out-video needs --frames N or --duration S");
    }};

namespace {

/// The pipeline's options from the command line.
PipelineOptions pipelineOptionsFrom(const Settings& s, const FrameSource& source) {
  const StreamSettings& st = s.stream;
  PipelineOptions opt;
  opt.layout = layoutSpec(s.panorama, &source, true);
  if (s.panorama.circleAuto) {  // the ball followed from frame to frame
    std::optional<LensCalibration> camera;
    if (s.panorama.lens) camera = readLensCalibration(*s.panorama.lens);
    opt.followBall = PipelineOptions::FollowBall{
        [base = opt.layout, camera](glm::vec3 circle) {
          LayoutSpec l = base;
          l.circle = circle;
          if (camera) l.lens = makeBallModel(*camera, circle);
          return l;
        },
        [name = source.describe()](const std::string& line) {
          std::fprintf(stderr, "liveprobe: %s: %s\n", name.c_str(), line.c_str());
        },
        [camera](int w, int h) {
          return camera ? ballSearchWindow(*camera, w, h) : std::optional<FrameWindow>();
        }};
  }
  opt.photometry = photometryFrom(st);
  if (s.panorama.rotate || s.panorama.flip) opt.rotation = envOrientation(s.panorama);
  opt.smoothSeconds = st.smooth;
  opt.loop = st.loop;
  opt.reduce = st.reduce;
  opt.lights = chooseLights(s);
  opt.threads = unsigned(st.threads);
  opt.maxFrames = s.output.frames.value_or(-1);
  opt.interrupted = stopRequested;  // a paced wait ends within kStopPollSeconds of Ctrl-C
  opt.holdBelow = st.holdBelow;
  // A bracketed source is merged; so is any 8-bit stream with its own response (a bracket of one
  // frame: the response's three curves decode it).
  const BracketedSource* bracket = bracketOf(source);
  if (bracket || st.response) {
    MergeOptions m;
    m.frames = bracket ? bracket->bracketFrames() : 1;
    if (auto told = responseOption(st))  // the merge decodes with the curve it is told
      m.response = std::move(*told);
    else if (bracket && !bracket->bracketResponse().empty())
      m.response =
          CameraResponse::parse(bracket->bracketResponse(), source.describe() + ": response");
    m.equirect = opt.layout.layout == Layout::Equirect;
    opt.bracket = m;
  }
  return opt;
}

/// The viewer of a stream, and what it keeps of the stream's frames.
struct StreamView {
  std::unique_ptr<Viewer> v;
  bool autoExposure = true, haveLighting = false;
  LayoutSpec layout;
  bool layoutGiven = false;  ///< --layout named it
  std::string source;

  /// Uploads a frame's lighting and background; returns the upload time in ms.
  double use(const ProcessedFrame& f) {
    StageClock clock;
    const Background& b = f.background;
    if (!haveLighting && layout.lens) {  // the first frame: is it the lens scaled?
      // (A lens's, or a traced ball's, background is the frame resampled to an equirect: the
      // lens is asked about the frame itself.)
      const std::string scaled = layout.lens->scaling(f.width, f.height);
      if (!scaled.empty()) warn(source + ": " + scaled);
    } else if (!haveLighting && !b.empty()) {  // does the frame's shape fit the layout?
      warnIfLayoutLooksWrong(source, layout, layoutGiven, b.width(), b.height(),
                             b.image ? b.image->rgb.data() : nullptr);
    }
    if (!haveLighting && autoExposure)
      v->state.shading.exposure = cli::autoExposure(f.radiance, true, f.lights);
    haveLighting = true;
    gl::Renderer& r = *v->renderer;
    r.setLighting(f.radiance, f.lights);
    v->gpuTimer->begin(gl::GpuTimer::Upload);
    setBackground(r, b);
    v->gpuTimer->end();
    // The time to hand the data to GL, not waiting for it (no glFinish stalling every frame);
    // `liveprobe bench` times the upload to completion.
    return clock.lap(Stage::Upload);
  }
};

/// A drawn frame's GPU times: capture's projection, the viewer's upload and render.
GpuTimes shownGpu(const Viewer& v, const ProcessedFrame& f) {
  return {v.gpuMs(gl::GpuTimer::Upload), f.gpu.project, v.gpuMs(gl::GpuTimer::Render)};
}

/// Headless replay: every frame drawn, in order, and written.
void runOffline(CapturePipeline& pipeline, StreamView& view, const StreamOutputs& out,
                StreamTally& tally, Progress& progress, const RecordSinks& sinks) {
  Viewer& v = *view.v;
  std::optional<ProcessedFrame> f;
  double uploadMs = 0;
  ViewerLoop loop;
  loop.before = [&](const std::vector<KeyAction>&) {
    f = pipeline.waitNext();
    if (!f) return Turn::Stop;
    uploadMs = view.use(*f);
    return Turn::Draw;
  };
  loop.drawn = [&](double ms) {  // (a Ctrl-C after this frame ends the loop: the rest is dropped)
    const glm::ivec2 fb = v.ctx->framebufferSize();
    const auto px = gl::Renderer::readRgb8(fb);
    const double latency = 1000.0 * (monotonicSeconds() - f->captureTime);
    ++tally.drawn;
    const GpuTimes gpu = shownGpu(v, *f);
    recordSample(tally, *f, uploadMs, ms, latency, v.hud.get(), pipeline.stats(), sinks, gpu);
    sinks.shown(*f, {ms, latency, gpu});
    out.writeFrame(*f, fb, px);
    progress.update(std::int64_t(tally.drawn));
    return true;
  };
  v.run(loop);
}

/// A window (or a camera headless): the newest coefficients, never waiting for capture.
void runInteractive(CapturePipeline& pipeline, StreamView& view, StreamTally& tally,
                    Progress& progress, bool live, const std::string& title,
                    const RecordSinks& sinks) {
  Viewer& v = *view.v;
  bool wasPaused = false;
  std::optional<ProcessedFrame> f;
  double uploadMs = 0;
  PipelineStats st;
  ViewerLoop loop;
  loop.canPause = !live;
  loop.before = [&](const std::vector<KeyAction>&) {
    if (v.state.paused != wasPaused) pipeline.setPaused(wasPaused = v.state.paused);
    for (; v.state.steps > 0; --v.state.steps) pipeline.step();
    uploadMs = 0;
    f = pipeline.takeLatest();
    if (f) {
      uploadMs = view.use(*f);
      return Turn::Draw;
    }
    if (pipeline.finished()) return Turn::Stop;
    return v.window() ? Turn::Draw : Turn::Wait;  // a window redraws (input, the HUD)
  };
  loop.drawn = [&](double ms) {
    st = pipeline.stats();  // once a frame, for the HUD, progress and title
    if (v.hud) v.hud->setSourceWaiting(pipeline.source().waitingFor());
    if (f) {
      ++tally.drawn;
      const double latency = 1000.0 * (monotonicSeconds() - f->captureTime);
      const GpuTimes gpu = shownGpu(v, *f);
      recordSample(tally, *f, uploadMs, ms, latency, v.hud.get(), st, sinks, gpu);
      sinks.shown(*f, {ms, latency, gpu});
      progress.update(std::int64_t(st.captured));
    }
    return true;
  };
  loop.title = [&] {
    return std::pair{"liveprobe - " + title + " - frame " + std::to_string(st.captured),
                     std::string(v.state.paused ? " - paused" : "")};
  };
  v.run(loop);
}

/// How one run goes: the pipeline's options and what the loop decides from the source.
struct StreamPlan {
  PipelineOptions opt;
  bool live = false;
  bool headless = false;                   ///< as the GL context came up (setHeadless)
  bool headlessAsked = false;              ///< --headless (not only the want of a display)
  bool quiet = false;                      ///< --quiet
  bool endless = false;                    ///< no end but Ctrl-C
  std::pair<int, int> size, headlessSize;  ///< the view's, in a window and headless
  double fps = 0;
  std::string description;
  std::string projection = "the CPU";  ///< where frames are projected (streamProjection)
  gl::Camera camera;  ///< the model and the camera, read before any output is opened
  Mesh mesh;
};

StreamPlan planStream(const Settings& s, const FrameSource& source, bool live) {
  StreamPlan p;
  p.headlessAsked = s.scene.headless, p.quiet = s.output.quiet;
  p.live = live;
  p.opt = pipelineOptionsFrom(s, source);
  p.camera = cameraFrom(s.scene);
  p.mesh = meshFrom(s.scene);
  p.fps = source.fps();
  p.description = source.describe();
  // live: --view-size (its --size is the camera's)
  const std::optional<Size> asked = live ? s.live.viewSize : s.output.size;
  p.size = asked.value_or(Size{1280, 720});
  p.headlessSize = asked.value_or(Size{640, 360});
  PipelineOptions& opt = p.opt;
  if (s.output.duration) {
    const double d = *s.output.duration;
    const std::int64_t n = std::max<std::int64_t>(1, std::llround(d * (p.fps > 0 ? p.fps : 30.0)));
    opt.maxFrames = opt.maxFrames < 0 ? n : std::min(opt.maxFrames, n);
  }
  // (live says so on its first line, with the camera's description)
  p.endless = !live && opt.maxFrames < 0 && (opt.loop || p.description.rfind("synthetic", 0) == 0);
  opt.keepImages = true;  // the background can be switched on at any time (B), and the HUD shows it
  return p;
}

/// What follows from the GL context that came up, a window or headless: how frames are handed
/// over and paced.
void setHeadless(const StreamSettings& st, StreamPlan& p, bool headless) {
  p.headless = headless;
  p.opt.handoff = headless && !p.live ? Handoff::Every : Handoff::Latest;
  // A window plays in real time; so does a headless replay that serves or publishes (its readers
  // want the source's pace, not as fast as it renders), or that asks with --realtime.
  p.opt.realtime = !p.live && (!headless || st.realtime || st.serve || st.publish);
}

/// At capture, on capture's thread: the record sinks (the stream, MQTT, --coeffs-out; none of
/// them waits on a reader) and --record's raw frames.
void wireCaptureOutputs(StreamPlan& p, StreamOutputs& out, RecordSinks& sinks,
                        const FrameSource& source) {
  if (out.coeffs)  // headless replay logs the drawn frames, with their render times
    addCoeffsSink(sinks, *out.coeffs, out.format,
                  p.headless && !p.live ? CoeffsLines::AtDraw : CoeffsLines::AtCapture);
  std::vector<RecordSink*> to;
  for (const auto& sink : sinks.all) to.push_back(sink.get());
  if (!to.empty())
    p.opt.onCaptured = [to, format = out.format, opening = sinks.opening,
                        said = std::make_shared<std::once_flag>()](const ProcessedFrame& f) {
      std::call_once(*said, [&] {
        for (const std::string& line : opening) std::fprintf(stderr, "%s\n", line.c_str());
      });
      FrameRecord record(f, format);
      for (RecordSink* sink : to) sink->publish(record);
    };
  // --record (live): the raw stream, finalised even when capture stops on a fault.
  if (VideoRecorder* rec = out.record.get()) {
    if (const BracketedSource* bracket = bracketOf(source))  // replayed through the same merge
      rec->setBracket(bracket->bracketFrames(), p.opt.bracket->response.json());
    p.opt.onFrame = [rec](const Frame& f) { rec->write(f); };
  }
}

/// The GL context, the renderer with its model, and the HUD (a window always has one: H shows
/// it, F1 the help).
StreamView openStreamView(const Settings& s, const StreamPlan& p) {
  StreamView view;
  view.v = std::make_unique<Viewer>(
      ViewerSpec{glBackend(s.scene), p.size, p.headlessSize, s.output.hud, s.output.noHud,
                 s.scene.fullResolution, true, s.scene.gpu},
      p.mesh);
  Viewer& v = *view.v;
  v.state.shading = shadingFrom(s.scene, Sh9{});
  v.state.camera = v.state.initialCamera = p.camera;
  view.autoExposure = !s.scene.exposure;
  view.layout = p.opt.layout;
  view.layoutGiven = s.panorama.layout.has_value();
  view.source = p.description;
  if (p.opt.rotation) v.renderer->setEnvOrientation(*p.opt.rotation);
  if (v.hud)
    v.hud->setSource(p.description, std::string(layoutName(p.opt.layout.layout)),
                     p.opt.smoothSeconds > 0);
  return view;
}

/// What the run says before it starts; the progress line (a file of known length shows its
/// total and an ETA without --frames).
Progress announceRun(const StreamPlan& p, const FrameSource& source, bool window, bool quiet) {
  if (p.endless && !window && !quiet)
    std::fprintf(stderr,
                 "liveprobe: %s has no end: running until Ctrl-C (or give --frames N or "
                 "--duration S)\n",
                 p.description.c_str());
  const std::int64_t length = p.live || p.opt.loop ? -1 : source.frameCount();
  const std::int64_t total =
      length > 0 && (p.opt.maxFrames < 0 || length < p.opt.maxFrames) ? length : p.opt.maxFrames;
  if (!p.endless && !p.live && !p.opt.loop && window && !quiet)
    std::fprintf(stderr, "liveprobe: the window closes after %s%s (--loop plays on)\n",
                 total > 0 ? (std::to_string(total) + " frames of ").c_str() : "the end of ",
                 p.description.c_str());
  return Progress(p.live ? "live" : "replay", total, quiet || window);
}

/// After the loop: the files kept or discarded, the summary, the exit code.
int finishStream(const StreamPlan& p, const PipelineStats& st, const StreamTally& tally,
                 StreamOutputs& out, const RecordSinks& sinks, const StreamView& view) {
  // Every stream client gets a clean close; --coeffs-out logs what was sent and never drawn.
  for (const auto& sink : sinks.all) sink->stop();
  // A camera's frames up to a fault are real data and are kept; a replay that failed keeps
  // nothing (the recorders' destructors discard what they wrote).
  const bool keep = st.error.empty() || p.live;
  if (out.record && keep) {
    out.record->finish();
    std::fprintf(stderr, "liveprobe: recorded %zu frames to %s\n", out.record->frames(),
                 out.record->path().c_str());
  }
  if (out.coeffs && keep) out.coeffs->commit();
  if (!st.error.empty()) throw Error(st.error);
  if (p.opt.followBall && st.captured == 0 && st.beforeBall > 0)
    throw Error(p.description + ": --circle auto found no mirror ball in " +
                std::to_string(st.beforeBall) +
                " frames (a circle from a tenth to a half of the frame's shorter side whose rim "
                "holds); give --circle cx,cy,r");
  if (out.video) out.video->finish();
  if (out.frames) out.frames->keep();
  printSummary(p.description, st, tally, p.opt.smoothSeconds, stopRequested(), sinks);
  if (p.opt.projectOnGpu) {
    std::fprintf(stderr, "  projected on %s: %zu of %zu frames\n", p.projection.c_str(),
                 st.projectedOnGpu, st.captured);
    if (p.opt.bracket) {
      const std::string kept = st.backgroundsOnGpu == 0
                                   ? ""
                                   : ", " + std::to_string(st.backgroundsOnGpu) +
                                         " kept there for the background (not read back)";
      std::fprintf(stderr, "  bracket merged on the GPU: %zu of %zu frames%s\n", st.mergedOnGpu,
                   st.captured, kept.c_str());
    }
  } else
    std::fprintf(stderr, "  projected on the CPU\n");
  // The GPU's own time, where a GPU takes part (a software rasterizer's is said to be none).
  if (p.opt.projectOnGpu || view.v->hasGpuTimer)
    std::fprintf(stderr, "  %s\n", gpuTimeLine(tally, view.v->ctx->describe()).c_str());
  if (p.live && !p.quiet) printCameraHints(tally, st, p.opt.bracket.has_value(), p.fps);
  // Headless with nowhere to put what it made (no display, and no output asked for): said, so
  // that a run which only measures is one by choice.
  if (p.headless && !out.frames && !out.video && !out.coeffs && !out.record && sinks.all.empty() &&
      !p.quiet)
    std::fprintf(stderr,
                 "liveprobe: %s: nothing was kept from this run (--out-dir DIR, --out-video FILE "
                 "or --coeffs-out FILE keep what it renders and measures)\n",
                 p.headlessAsked ? "headless" : "no display, so headless");
  if (view.v->dynamicResolution.active())
    std::fprintf(stderr, "  %s at the end (dynamic resolution; --full-resolution turns it off)\n",
                 view.v->dynamicResolution.describe().c_str());
  if (stopRequested()) return kExitInterrupted;
  // Publishing was asked for and nothing at all reached the broker: the run failed its purpose.
  for (const auto& sink : sinks.all)
    if (!sink->delivered() && st.captured > 0) return kExitRuntime;
  return 0;
}

// The pipeline and the render loop, for replay (a file) and live (a camera). A camera is never
// paced or held back: capture uses the latest-value handoff even headless, and --coeffs-out
// lines are written as frames are captured.
int runStream(const Args& a, std::unique_ptr<FrameSource> source, bool live) {
  installStopHandlers();
  const Settings& s = a.settings();
  StreamPlan plan = planStream(s, *source, live);
  StreamOutputs out = openOutputs(s, plan.fps, plan.description);
  RecordSinks sinks = openSinks(s.stream);
  StreamView view = openStreamView(s, plan);
  setHeadless(s.stream, plan, !view.v->window());
  try {
    plan.opt.projectOnGpu = streamProjection(s.scene.projection, *view.v->ctx, plan.projection);
  } catch (const gl::ContextError& e) {
    throw Error(std::string("GL: ") + e.what());
  }
  wireCaptureOutputs(plan, out, sinks, *source);
  Progress progress = announceRun(plan, *source, !plan.headless, s.output.quiet);

  CapturePipeline pipeline(std::move(source), plan.opt);
  pipeline.start();
  StreamTally tally;
  try {
    if (plan.headless && !live)
      runOffline(pipeline, view, out, tally, progress, sinks);
    else
      runInteractive(pipeline, view, tally, progress, live, plan.description, sinks);
  } catch (const gl::ContextError& e) {
    pipeline.stop();
    throw Error(std::string("GL: ") + e.what());
  }
  pipeline.stop();
  progress.finish();
  return finishStream(plan, pipeline.stats(), tally, out, sinks, view);
}

}  // namespace

int runStreamForLive(const Args& a, std::unique_ptr<FrameSource> camera) {
  return runStream(a, std::move(camera), true);
}

int runReplay(const Args& a) {
  const std::string sourceName = a.positional().empty() ? defaultRecording() : a.positional()[0];
  const Settings& s = a.settings();
  SourceOptions so;
  so.fps = s.stream.fps.value_or(30.0);
  layoutSpec(s.panorama, nullptr, true);  // option errors before the file is opened
  return runStream(a, openSource(sourceName, so), false);
}

const CommandSpec kRecordSpec{
    "record",
    "SOURCE",
    "Saves a source for replay: FFV1 in .mkv (lossless), MJPEG in .avi or H.264 in .mp4, with a\n"
    "sidecar FILE.json holding the exposure and every frame's timestamp. Float (HDR) sources are\n"
    "stored as sRGB 8-bit with an exposure that puts the first frame's 99.9th percentile at 95%\n"
    "(a sun's few pixels clip, as on a camera). Synthetic sources record 5 seconds unless\n"
    "--frames or --duration says otherwise. Ctrl-C stops cleanly: what was recorded is\n"
    "finalised, exit 130.",
    {opt::out("FILE",
              "output video (.mkv, .avi or .mp4), or a frame-number pattern of .exr or .hdr "
              "frames (frames/%04d.exr: linear radiance, a sun unclipped); required",
              {".mkv", ".avi", ".mp4", ".exr", ".hdr"}),
     opt::frames("number of frames to record", 1000000000, ""),
     opt::duration("seconds of the source to record"),
     opt::fps("frame rate of image sequences and of the recording", {1, 1000}, "the source's"),
     quietOption()},
    1,
    1,
    LP_SOURCE_KINDS,
    [](const Settings& s) {
      if (!s.output.out) throw Error("--out FILE.mkv is required");
    }};

int runRecord(const Args& a) {
  installStopHandlers();
  const Settings& s = a.settings();
  SourceOptions so;
  so.fps = s.stream.fps.value_or(30.0);
  std::int64_t frames = s.output.frames.value_or(-1);
  auto source = openSource(a.positional()[0], so);
  const double fps = s.stream.fps ? so.fps : source->fps();
  if (s.output.duration) {
    const std::int64_t n = std::max<std::int64_t>(1, std::llround(*s.output.duration * fps));
    frames = frames < 0 ? n : std::min(frames, n);
  }
  if (frames < 0 && a.positional()[0].rfind("synthetic", 0) == 0)
    frames = std::int64_t(std::lround(5 * fps));
  VideoRecorder rec(*s.output.out, fps, source->describe());
  Progress progress("record", frames, s.output.quiet);
  Frame f;
  while ((frames < 0 || std::int64_t(rec.frames()) < frames) && !stopRequested() &&
         source->next(f)) {
    rec.write(f);
    progress.update(std::int64_t(rec.frames()));
  }
  progress.finish();
  rec.finish();
  std::fprintf(stderr, "liveprobe: %s: %zu frame%s at %.3g fps from %s%s\n", s.output.out->c_str(),
               rec.frames(), rec.frames() == 1 ? "" : "s", fps, source->describe().c_str(),
               stopRequested() ? "; stopped by a signal" : "");
  return stopRequested() ? kExitInterrupted : 0;
}

}  // namespace lp::cli
