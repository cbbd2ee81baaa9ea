// Dynamic lighting from streams: replay (a recording, video, sequence or the synthetic sky,
// re-projected every frame, drawing a model) and record (save a source for replay).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "capture/error.h"
#include "capture/pipeline.h"
#include "capture/recorder.h"
#include "coeffs_io.h"
#include "commands.h"
#include "scene.h"

namespace lp::cli {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

std::string defaultRecording() {
  if (const char* e = std::getenv("LIVEPROBE_DEFAULT_RECORDING")) return e;
  return std::string(LIVEPROBE_SOURCE_DIR) + "/recordings/sky.mkv";
}

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

/// One line of --coeffs-out. `renderMs` < 0 writes null (a frame that was never drawn).
std::string coeffsLine(const ProcessedFrame& f, double renderMs) {
  nlohmann::ordered_json j;
  j["frame"] = f.index;
  j["time"] = f.timestamp;
  j["coefficients"] = coefficientsJson(f.radiance);
  nlohmann::ordered_json t;
  t["grab"] = f.times.grabMs;
  t["convert"] = f.times.convertMs;
  t["project"] = f.times.projectMs;
  t["render"] = renderMs < 0 ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(renderMs);
  j["timings_ms"] = t;
  return j.dump();
}

/// A text file written under a temporary name and renamed by commit(); removed if never
/// committed, so an aborted run leaves nothing half-written.
class AtomicTextFile {
 public:
  explicit AtomicTextFile(const std::string& path) : path_(path) {
    const fs::path p(path);
    const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw Error(path + ": folder " + dir.string() + " does not exist");
    tmp_ = (dir / ("." + p.filename().string() + ".tmp")).string();
    out_.open(tmp_);
    if (!out_) throw Error(path + ": cannot write");
  }
  ~AtomicTextFile() {
    if (!committed_) {
      out_.close();
      std::error_code ec;
      fs::remove(tmp_, ec);
    }
  }
  void line(const std::string& s) {
    std::lock_guard lock(mutex_);
    out_ << s << '\n';
  }
  void commit() {
    out_.close();
    if (!out_) throw Error(path_ + ": write failed");
    std::error_code ec;
    fs::rename(tmp_, path_, ec);
    if (ec) throw Error(path_ + ": cannot rename into place: " + ec.message());
    committed_ = true;
  }

 private:
  std::string path_, tmp_;
  std::ofstream out_;
  std::mutex mutex_;
  bool committed_ = false;
};

glm::mat3 parseRotation(const std::string& text) {
  std::vector<float> v;
  std::stringstream s(text);
  for (std::string part; std::getline(s, part, ',');) v.push_back(float(parseNumber(part, "--rotate")));
  if (v.size() != 3) throw Error("--rotate " + text + ": expected yaw,pitch,roll in degrees");
  return rotationYawPitchRoll(v[0], v[1], v[2]);
}

Photometry photometryFromArgs(const Args& a) {
  Photometry p;
  const std::string g = a.get("--gamma", "srgb");
  if (g != "srgb") {
    p.gamma = float(parseNumber(g, "--gamma"));
    if (!(p.gamma > 0.2f && p.gamma < 5.0f)) throw Error("--gamma " + g + ": expected srgb or a gamma in (0.2, 5)");
  }
  p.exposure = float(a.number("--input-exposure", 1.0));
  if (!(p.exposure > 0)) throw Error("--input-exposure " + a.get("--input-exposure") + ": must be positive");
  return p;
}

}  // namespace

std::vector<OptionSpec> streamOptions() {
  auto o = layoutOptions();
  o.insert(o.end(), {{"--gamma", "srgb|G", "8-bit decoding: the sRGB curve (default) or code^G"},
                     {"--input-exposure", "X", "linear radiance scale applied to the input (default 1)"},
                     {"--rotate", "YAW,PITCH,ROLL", "rotate the lighting (degrees; SH rotation, no resampling)"},
                     {"--smooth", "SECONDS", "exponential moving average of the coefficients"},
                     {"--fps", "F", "frame rate of image sequences (default 30)"},
                     {"--reduce", "F", "equirect: project an F x F area average (faster; error in README)"},
                     {"--threads", "N", "threads for one frame's projection (default 2)"}});
  return o;
}

const CommandSpec kReplaySpec{
    "replay",
    "[SOURCE] [--layout ...] [--loop] [--headless] [--frames N] [--coeffs-out FILE.jsonl]\n"
    "       [--out-dir DIR | --out-video FILE] [--rotate Y,P,R] [--smooth S] [model and look options]",
    "Replays a panoramic stream, re-projecting the nine coefficients every frame, and draws the\n"
    "model lit by them with the frame behind it. SOURCE: a video (mp4, webm, mkv, avi), an image\n"
    "sequence (folder or printf pattern), an image, a folder of six cube faces, or\n"
    "synthetic[:WxH[@FPS]]; default: the bundled recording recordings/sky.mkv.\n"
    "In a window capture runs in real time on its own thread and the newest coefficients are\n"
    "drawn (stale frames are dropped and counted); headless (--headless, or no display) every\n"
    "frame is drawn, and written with --out-dir or --out-video.",
    [] {
      auto o = streamOptions();
      o.insert(o.end(), {{"--loop", "", "start again at the end of the source"},
                         {"--frames", "N", "stop after N frames"},
                         {"--size", "WxH", "window or frame size (default 1280x720; headless 640x360)"},
                         {"--coeffs-out", "FILE.jsonl", "one JSON line per frame: coefficients and stage timings"},
                         {"--out-dir", "DIR", "headless: write each rendered frame as DIR/frame_NNNNNN.png"},
                         {"--out-video", "FILE", "headless: write the rendered frames as a video (.mkv/.avi)"}});
      auto scene = sceneOptions();
      o.insert(o.end(), scene.begin(), scene.end());
      return o;
    }(),
    0, 1};

namespace {

// The pipeline and the render loop, for replay (a file) and live (a camera). A camera is never
// paced or held back: capture uses the latest-value handoff even headless, and --coeffs-out
// lines are written as frames are captured.
int runStream(const Args& a, std::unique_ptr<FrameSource> source, bool live) {
  PipelineOptions opt;
  opt.layout = layoutFromArgs(a);
  opt.photometry = photometryFromArgs(a);
  if (a.has("--rotate")) opt.rotation = parseRotation(a.get("--rotate"));
  opt.smoothSeconds = a.number("--smooth", 0.0);
  if (opt.smoothSeconds < 0) throw Error("--smooth " + a.get("--smooth") + ": must be >= 0");
  opt.loop = a.has("--loop");
  opt.reduce = a.integer("--reduce", 1);
  if (opt.reduce < 1 || opt.reduce > 64) throw Error("--reduce " + a.get("--reduce") + ": expected 1 to 64");
  opt.threads = unsigned(std::clamp(a.integer("--threads", 2), 1, 64));
  opt.maxFrames = a.integer("--frames", -1);
  if (a.has("--frames") && opt.maxFrames < 1) throw Error("--frames " + a.get("--frames") + ": must be at least 1");
  if (a.has("--out-dir") && a.has("--out-video")) throw Error("give --out-dir or --out-video, not both");
  const gl::Camera cameraInit = cameraFromArgs(a);
  const Mesh mesh = meshFromArgs(a);
  const double fps = source->fps();
  const std::string description = source->describe();

  const bool headless = a.has("--headless") || !(std::getenv("DISPLAY") || std::getenv("WAYLAND_DISPLAY"));
  const std::string sizeOpt = live ? "--view-size" : "--size";  // live: --size is the camera's
  const auto size = parseSize(a.get(sizeOpt, headless ? "640x360" : "1280x720"), sizeOpt);
  if (headless && opt.loop && opt.maxFrames < 0) throw Error("--loop without a window needs --frames N");
  opt.handoff = headless && !live ? Handoff::Every : Handoff::Latest;
  opt.realtime = !headless && !live;
  gl::ShadingSettings shading = shadingFromArgs(a, Sh9{});
  const bool autoExposureWanted = a.get("--exposure", "auto") == "auto";
  opt.keepImages = shading.background;

  std::unique_ptr<AtomicTextFile> coeffsOut;
  if (a.has("--coeffs-out")) coeffsOut = std::make_unique<AtomicTextFile>(a.get("--coeffs-out"));
  const std::string outDir = a.get("--out-dir");
  if (!outDir.empty()) {
    std::error_code ec;
    fs::create_directories(outDir, ec);
    if (!fs::is_directory(outDir)) throw Error("--out-dir " + outDir + ": cannot create the folder");
  }
  std::unique_ptr<VideoRecorder> outVideo;
  if (a.has("--out-video")) outVideo = std::make_unique<VideoRecorder>(a.get("--out-video"), fps, "liveprobe replay of " + description);
  if ((!headless || live) && coeffsOut) {
    AtomicTextFile* file = coeffsOut.get();
    opt.onCaptured = [file](const ProcessedFrame& f) { file->line(coeffsLine(f, -1)); };
  }
  // --record (live): the raw stream, finalised even when capture stops on a fault.
  std::unique_ptr<VideoRecorder> recorder;
  if (a.has("--record")) {
    recorder = std::make_unique<VideoRecorder>(a.get("--record"), fps, description, source->radianceScale());
    VideoRecorder* rec = recorder.get();
    opt.onFrame = [rec](const Frame& f) { rec->write(f); };
  }

  auto ctx = openContext(headless ? gl::Backend::Headless : gl::Backend::Auto, size);
  gl::Camera camera = cameraInit;
  gl::Renderer renderer;
  loadModel(renderer, mesh);
  CapturePipeline pipeline(std::move(source), opt);
  pipeline.start();

  std::vector<double> grab, convert, project, render;
  std::size_t drawn = 0, saturated = 0;
  bool haveLighting = false;
  auto useFrame = [&](const ProcessedFrame& f) {
    if (!haveLighting && autoExposureWanted) shading.exposure = autoExposure(f.radiance);
    haveLighting = true;
    renderer.setLighting(f.radiance);
    if (f.image) setBackground(renderer, *f.image, opt.layout);
    if (f.raw) setBackground(renderer, *f.raw, opt.layout, f.rawScale);
    grab.push_back(f.times.grabMs);
    convert.push_back(f.times.convertMs);
    project.push_back(f.times.projectMs);
    saturated += f.saturated;
  };
  try {
    if (headless && !live) {
      while (auto f = pipeline.waitNext()) {
        const auto t0 = Clock::now();
        useFrame(*f);
        const glm::ivec2 fb = ctx->framebufferSize();
        renderer.draw(fb, camera, shading);
        const auto px = gl::Renderer::readRgb8(fb);
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        render.push_back(ms);
        ++drawn;
        if (coeffsOut) coeffsOut->line(coeffsLine(*f, ms));
        if (!outDir.empty()) {
          char name[32];
          std::snprintf(name, sizeof name, "frame_%06llu.png", static_cast<unsigned long long>(f->index));
          saveRgb8((fs::path(outDir) / name).string(), fb.x, fb.y, px.data());
        }
        if (outVideo) {
          Frame out;
          out.format = PixelFormat::Bgr8;
          out.width = fb.x, out.height = fb.y;
          out.timestamp = f->timestamp;
          out.bgr8.resize(px.size());
          for (std::size_t i = 0; i < px.size(); i += 3)
            out.bgr8[i] = px[i + 2], out.bgr8[i + 1] = px[i + 1], out.bgr8[i + 2] = px[i];
          outVideo->write(out);
        }
      }
    } else {
      auto fpsT0 = Clock::now();
      std::size_t fpsFrames = 0;
      while (!ctx->shouldClose()) {
        applyInput(camera, ctx->pollEvents());
        if (auto f = pipeline.takeLatest()) useFrame(*f);
        else if (pipeline.finished()) break;
        else if (headless) {  // live, headless: nothing new to draw yet
          std::this_thread::sleep_for(std::chrono::milliseconds(2));
          continue;
        }
        const auto t0 = Clock::now();
        renderer.draw(ctx->framebufferSize(), camera, shading);
        ctx->present();
        render.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
        ++drawn, ++fpsFrames;
        const double s = std::chrono::duration<double>(Clock::now() - fpsT0).count();
        if (s >= 2.0) {
          std::fprintf(stderr, "liveprobe replay: %.1f frames/s drawn, %zu captured, %zu dropped\n",
                       fpsFrames / s, pipeline.stats().captured, pipeline.stats().dropped);
          fpsT0 = Clock::now(), fpsFrames = 0;
        }
      }
    }
  } catch (const gl::ContextError& e) {
    pipeline.stop();
    throw Error(std::string("GL: ") + e.what());
  }
  pipeline.stop();
  const PipelineStats st = pipeline.stats();
  if (recorder) {
    recorder->finish();
    std::fprintf(stderr, "liveprobe: recorded %zu frames to %s\n", recorder->frames(), recorder->path().c_str());
  }
  if (coeffsOut && (st.error.empty() || live)) coeffsOut->commit();  // a camera's frames up to a fault are real data
  if (!st.error.empty()) throw Error(st.error);
  if (outVideo) outVideo->finish();

  std::fprintf(stderr,
               "liveprobe replay: %s: %zu frames captured, %zu drawn, %zu dropped (stale), %zu skipped (corrupt)%s%s\n"
               "  median ms: grab %.2f, convert %.2f, project %.2f, render %.2f; saturated values %.1f per frame\n",
               description.c_str(), st.captured, drawn, st.dropped, st.skipped,
               st.endReason.empty() ? "" : "; ", st.endReason.c_str(), median(grab), median(convert),
               median(project), median(render), st.captured ? double(saturated) / double(grab.size()) : 0.0);
  if (opt.smoothSeconds > 0)
    std::fprintf(stderr, "  --smooth %.3g s: lighting lags a step change by %.3g s (63%% of the step)\n",
                 opt.smoothSeconds, opt.smoothSeconds);
  return 0;
}

}  // namespace

int runStreamForLive(const Args& a, std::unique_ptr<FrameSource> camera) {
  return runStream(a, std::move(camera), true);
}

int runReplay(const Args& a) {
  const std::string sourceName = a.positional().empty() ? defaultRecording() : a.positional()[0];
  SourceOptions so;
  so.fps = a.number("--fps", 30.0);
  if (!(so.fps > 0 && so.fps <= 1000)) throw Error("--fps " + a.get("--fps") + ": expected a rate in (0, 1000]");
  layoutFromArgs(a);  // option errors before the file is opened
  return runStream(a, openSource(sourceName, so), false);
}

const CommandSpec kRecordSpec{
    "record",
    "SOURCE --out FILE.mkv|FILE.avi [--frames N] [--fps F]",
    "Saves a source for replay: FFV1 in .mkv (lossless) or MJPEG in .avi, with a sidecar\n"
    "FILE.json holding the exposure and every frame's timestamp. Float (HDR) sources are stored\n"
    "as sRGB 8-bit with an exposure that puts the first frame's brightest pixel at 95%.\n"
    "Synthetic sources record 5 seconds unless --frames says otherwise.",
    {{"--out", "FILE", "output video (.mkv or .avi)"},
     {"--frames", "N", "number of frames to record"},
     {"--fps", "F", "frame rate of image sequences and of the recording (default: the source's)"}},
    1, 1};

int runRecord(const Args& a) {
  if (!a.has("--out")) throw Error("record: --out FILE.mkv is required");
  SourceOptions so;
  so.fps = a.number("--fps", 30.0);
  auto source = openSource(a.positional()[0], so);
  const double fps = a.has("--fps") ? so.fps : source->fps();
  std::int64_t frames = a.integer("--frames", -1);
  if (frames < 0 && a.positional()[0].rfind("synthetic", 0) == 0) frames = std::int64_t(std::lround(5 * fps));
  VideoRecorder rec(a.get("--out"), fps, source->describe(), source->radianceScale());
  Frame f;
  while ((frames < 0 || std::int64_t(rec.frames()) < frames) && source->next(f)) rec.write(f);
  rec.finish();
  std::fprintf(stderr, "liveprobe record: %s: %zu frames at %.3g fps from %s\n", a.get("--out").c_str(),
               rec.frames(), fps, source->describe().c_str());
  return 0;
}

}  // namespace lp::cli
