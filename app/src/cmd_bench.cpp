// liveprobe bench: a frame-time regression run of the whole replay pipeline, headless.

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>
#include <thread>

#include "baseline.h"
#include "commands.h"
#include "environment.h"
#include "liveprobe/capture/atomic_file.h"
#include "liveprobe/capture/open_source.h"
#include "liveprobe/capture/photometry.h"
#include "liveprobe/capture/pipeline.h"
#include "liveprobe/capture/resample.h"
#include "liveprobe/capture/stages.h"
#include "liveprobe/exchange/coeffs_io.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/frame/input_file.h"
#include "liveprobe/gl/gpu_projector.h"
#include "liveprobe/gl/gpu_timer.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/executor.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/projector.h"
#include "liveprobe/sh/simd.h"
#include "progress.h"
#include "scene.h"
#include "scene_gl.h"
#include "viewer.h"

namespace lp::cli {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
// The stages bench times, in the profiler's order (liveprobe/capture/stages.h; bench merges no
// bracket); arrays below are indexed by position in this list.
constexpr std::array kBenchStages = {Stage::Grab,   Stage::Convert, Stage::Project, Stage::Resample,
                                     Stage::Upload, Stage::Render,  Stage::Readback};
constexpr int kBenchStageCount = int(kBenchStages.size());
// A stage's name (the names are literals: NUL-terminated).
const char* stageLabel(int s) { return stageName(kBenchStages[std::size_t(s)]).data(); }

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Busy-waits, so an injected delay costs CPU time like real work does.
void spin(double ms) {
  const auto end = Clock::now() + std::chrono::duration<double, std::milli>(ms);
  while (Clock::now() < end) {
  }
}

// The calibration kernel: a fixed amount of the machine's own kind of work (projecting a fixed
// synthetic frame, single thread), timed in the same run. Stage times are divided by it, so a
// slower machine is not a regression. It is the machine's speed, not its load: the fastest of
// many repetitions of a few milliseconds each (shorter than a scheduler's time slice), since a
// repetition that other work interrupts only reads slower. The repetitions are spread over the
// whole run (one before each frame) and over every CPU the process may use, in turn: on a 2-core
// virtual machine one core could be slower for seconds (its host busy), and 21 repetitions in a
// row, on whichever core, read 3.2 to 4.9 ms from one run to the next while the stages did not
// move; spread, ten runs read 3.28 to 3.61 ms. (A median, not the fastest, read 2.5 ms in one run
// and 6.4 ms in the next on two busy cores.) It runs on the scalar path whatever the CPU offers:
// the stages it stands for (decode, GL on llvmpipe) gain little from AVX-512, so a kernel on the
// widest path would make a machine that has it look slower than it is (a render of 14 ms read as
// 22 against an AVX2 baseline).
class CalibrationKernel {
 public:
  CalibrationKernel() : proj_(Layout::Equirect, 512, 256) {
    renderSyntheticSky(512, 256, 0.5, sky_);
  }
  /// One repetition, timed; the fastest so far is speed().
  void time() {
    struct Path {  // the scalar path for the kernel, the best one again after it
      std::string was = simd::current();
      Path() { simd::select("scalar"); }
      ~Path() { simd::select(was); }
    } path;
    const auto t0 = Clock::now();
    Sh9 s;
    const OnCpu on(count_++);
    for (int r = 0; r < 10; ++r) s += proj_.project(PanoramaView::rgbF32(sky_.data(), 512, 256));
    volatile float sink = s.c[0].x;
    (void)sink;
    best_ = std::min(best_, msSince(t0));
  }
  double speed() const { return best_; }

 private:
  /// The calling thread on the n-th of the CPUs it may run on (in turn), for its lifetime.
  class OnCpu {
   public:
    explicit OnCpu(std::size_t n) {
      if (pthread_getaffinity_np(pthread_self(), sizeof was_, &was_) != 0) return;
      const int count = CPU_COUNT(&was_);
      if (count < 2) return;
      int k = int(n % std::size_t(count));
      for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
        if (CPU_ISSET(cpu, &was_) && k-- == 0) {
          cpu_set_t one;
          CPU_ZERO(&one);
          CPU_SET(cpu, &one);
          pinned_ = pthread_setaffinity_np(pthread_self(), sizeof one, &one) == 0;
          break;
        }
    }
    ~OnCpu() {
      if (pinned_) pthread_setaffinity_np(pthread_self(), sizeof was_, &was_);
    }
    OnCpu(const OnCpu&) = delete;
    OnCpu& operator=(const OnCpu&) = delete;

   private:
    cpu_set_t was_{};
    bool pinned_ = false;
  };
  std::vector<float> sky_;
  Projector proj_;
  std::size_t count_ = 0;
  double best_ = std::numeric_limits<double>::infinity();
};

// How much other programs held this process back: over its threads, the time each waited on a
// run queue for a CPU against the time it ran (Linux's scheduler statistics,
// /proc/self/task/*/schedstat: run ns, wait ns, timeslices). 1 + wait / run is the slowdown that
// sharing the CPUs alone explains: about 1.06 on an idle 2-core machine (bench's own threads wait
// for each other a little), 4.1 beside six stress-ng workers there. Runs are compared by its
// ratio to the baseline's. The calibration kernel, the fastest of many short repetitions, sees the
// machine's speed and not this; a stage's time sees both.
class Contention {
 public:
  Contention() : start_(read()) {}
  /// 1 + waited / ran since construction, over the threads alive now (a thread that ended took
  /// its counts with it); 1 where the kernel keeps no statistics.
  double factor() const {
    double run = 0, wait = 0;
    for (const auto& [tid, now] : read()) {
      const auto was = start_.find(tid);
      const Times before = was == start_.end() ? Times{} : was->second;
      run += now.run - before.run, wait += now.wait - before.wait;
    }
    return run > 0 && wait > 0 ? 1.0 + wait / run : 1.0;
  }

 private:
  struct Times {
    double run = 0, wait = 0;
  };
  static std::map<std::string, Times> read() {
    std::map<std::string, Times> out;
    std::error_code ec;
    for (const auto& t : fs::directory_iterator("/proc/self/task", ec)) {
      std::ifstream in(t.path() / "schedstat");
      Times v;
      if (in >> v.run >> v.wait) out[t.path().filename().string()] = v;
    }
    return out;
  }
  std::map<std::string, Times> start_;
};

constexpr int kWarmup =
    3;  // frames at the start of each run shown as warm-up (caches, JIT of llvmpipe's shaders)

/// Frames' stage times stacked, one line a frame, into `data`; the totals.
std::vector<double> writeStackedStages(
    const std::string& data, const std::string& path,
    const std::vector<std::array<double, kBenchStageCount>>& frames) {
  std::vector<double> total;
  std::ofstream d(data);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    double cum = 0;
    d << i;
    for (double v : frames[i]) d << ' ' << (cum += v);
    d << '\n';
    total.push_back(cum);
  }
  if (!d) throw Error(path + ": cannot write the plot's data beside it");
  return total;
}

/// A histogram of the totals in `bins` bins up to `top`, into `hist`.
void writeHistogram(const std::string& hist, const std::vector<double>& total, double top,
                    int bins) {
  const double width = top / bins;
  std::vector<int> counts(std::size_t(bins), 0);
  for (double t : total) counts[std::size_t(std::min(bins - 1, int(t / width)))]++;
  std::ofstream h(hist);
  for (int b = 0; b < bins; ++b) h << (b + 0.5) * width << ' ' << counts[std::size_t(b)] << '\n';
}

/// The gnuplot script: the stacked stages with the warm-up bands, then the histogram with the
/// median and p95 marked.
std::string plotScript(const std::string& png, const std::string& data, const std::string& hist,
                       const std::string& title, std::size_t frameCount, int framesPerRun,
                       double top, int bins, double med, double p95) {
  std::ostringstream g;
  g << "set terminal pngcairo size 1400,480 font 'sans,10'\nset output '" << png << "'\n"
    << "set multiplot layout 1,2 title '" << title << "'\n"
    << "set style fill solid 0.85 noborder\nset grid ytics lc rgb '#dddddd'\n"
    << "set xlabel 'frame (all runs in order)'\nset ylabel 'time per frame (ms), stages stacked'\n"
    << "set key outside right top vertical\nset yrange [0:" << top
    << "]\nset xrange [0:" << std::max<std::size_t>(1, frameCount - 1) << "]\n";
  for (std::size_t start = 0, k = 1; start < frameCount; start += std::size_t(framesPerRun), ++k)
    g << "set object " << k << " rect from " << start << ",0 to " << start + kWarmup - 1 << ","
      << top << " fc rgb '#909090' fs solid 0.35 noborder behind\n";
  g << "set label 1 'grey bands: the warm-up frames of each run' at graph 0.01, graph 0.96\n";
  const char* colours[kBenchStageCount] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#17becf",
                                           "#d62728", "#9467bd", "#8c564b"};
  g << "plot ";
  for (int s = kBenchStageCount - 1; s >= 0; --s) {
    g << "'" << data << "' using 1:" << (s + 2) << " with filledcurves x1 lc rgb '" << colours[s]
      << "' title '" << stageLabel(s) << "'";
    g << (s ? ", " : "\n");
  }
  g << "unset object\nunset label\nset xlabel 'frame time (ms)'\nset ylabel 'frames'\nset xrange "
       "[0:"
    << top << "]\nset yrange [0:*]\nset boxwidth " << top / bins * 0.9 << "\n"
    << "set arrow 1 from " << med << ", graph 0 to " << med
    << ", graph 1 nohead lc rgb '#2ca02c' lw 2\n"
    << "set arrow 2 from " << p95 << ", graph 0 to " << p95
    << ", graph 1 nohead lc rgb '#d62728' lw 2 dt 2\n"
    << "set label 2 sprintf('median %.2f ms', " << med << ") at " << med
    << ", graph 0.95 offset 1,0 tc rgb '#2ca02c'\n"
    << "set label 3 sprintf('p95 %.2f ms', " << p95 << ") at " << p95
    << ", graph 0.88 offset 1,0 tc rgb '#d62728'\n"
    << "plot '" << hist
    << "' using 1:2 with boxes lc rgb '#777777' title 'frames'\nunset multiplot\n";
  return g.str();
}

/// Runs gnuplot on `script`; lp::Error naming `path` with gnuplot's first line when it fails.
void runGnuplot(const std::string& script, const std::string& png, const std::string& path) {
  const std::string cmd = "gnuplot '" + script + "' 2>&1";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) throw Error(path + ": cannot run gnuplot");
  std::string said;
  char buf[256];
  while (std::fgets(buf, sizeof buf, pipe)) said += buf;
  const int rc = ::pclose(pipe);
  if (rc != 0 || !fs::exists(png)) {
    const auto nl = said.find('\n');
    throw Error(path + ": gnuplot failed (" +
                (rc == 127 * 256 ? std::string("not installed: scripts/deps installs gnuplot-nox")
                                 : said.substr(0, nl)) +
                ")");
  }
}

/// The frame-time plot, by gnuplot (pngcairo): stages stacked and filled against the frame
/// number, the warm-up frames shaded, and a histogram of the total with median and p95 marked.
/// Written to a temporary file and renamed; lp::Error when gnuplot is missing or fails.
void drawPlot(const std::string& path,
              const std::vector<std::array<double, kBenchStageCount>>& frames, int framesPerRun,
              const std::string& title) {
  AtomicOutput plot(path);  // gnuplot writes the PNG under its temporary name
  const std::string& png = plot.temporary();
  const std::string stem = png.substr(0, png.size() - fs::path(png).extension().string().size());
  const std::string data = stem + ".dat", hist = stem + ".hist", script = stem + ".gp";
  struct Cleanup {  // gnuplot's inputs
    std::vector<std::string> files;
    ~Cleanup() {
      std::error_code ec;
      for (const auto& f : files) fs::remove(f, ec);
    }
  } cleanup{{data, hist, script}};

  const std::vector<double> total = writeStackedStages(data, path, frames);
  const double med = percentile(total, 0.5), p95 = percentile(total, 0.95);
  // A warm-up spike does not set the scale.
  const double top = std::max(1e-3, percentile(total, 0.99) * 1.25);
  constexpr int kBins = 40;
  writeHistogram(hist, total, top, kBins);
  {
    std::ofstream f(script);
    f << plotScript(png, data, hist, title, frames.size(), framesPerRun, top, kBins, med, p95);
    if (!f) throw Error(path + ": cannot write the plot's script beside it");
  }
  runGnuplot(script, png, path);
  plot.commit();
}

}  // namespace

namespace {

/// --inject-delay STAGE=MS, parsed and checked as the line is read.
OptionSpec injectDelayOption(const std::string& group) {
  OptionSpec o =
      declared("--inject-delay", "STAGE=MS",
               "add MS milliseconds, at most 10000, of busy work to STAGE; repeatable", group);
  o.repeatable = true;
  o.set = [](Settings& s, const std::string& d) {
    const auto eq = d.find('=');
    int stage = -1;
    for (int k = 0; k < kBenchStageCount; ++k)
      if (eq != std::string::npos && d.substr(0, eq) == stageLabel(k)) stage = k;
    if (stage < 0) {
      std::string names;
      for (int k = 0; k < kBenchStageCount; ++k) names += std::string(" ") + stageLabel(k);
      throw Error("--inject-delay " + d + ": expected STAGE=MS, STAGE one of" + names);
    }
    const double ms = parseNumber(d.substr(eq + 1), "--inject-delay");
    if (ms < 0 || ms > 10000) throw Error("--inject-delay " + d + ": expected 0 to 10000 ms");
    s.bench.injectDelay.emplace_back(stage, ms);
  };
  return o;
}

}  // namespace

const CommandSpec kBenchSpec{
    "bench",
    "[SOURCE]",
    "Frame-time regression run: replays N frames headless through the whole pipeline (R times)\n"
    "and times each stage per frame: grab (decode), convert, project, resample (a layout GL does\n"
    "not draw as it is), upload, render, readback.\n"
    "Reports median, p95, p99 and max per stage. With --baseline it compares the medians of the\n"
    "runs, divided by a calibration kernel timed in the same run, prints a verdict and exits 1\n"
    "when a stage is slower than the baseline by more than --threshold percent (default 25) and\n"
    "by more than 0.5 ms. Where other programs held the run back (its threads waited for a CPU\n"
    "more than the baseline's did: see --max-contention) a slower stage is inconclusive (exit 2)\n"
    "unless it is slower than the load explains. --inject-delay slows one stage on purpose, to\n"
    "prove the detector works.\n"
    "SOURCE defaults to the bundled recording recordings/sky.mkv.",
    [] {
      auto o = layoutOptions();
      const std::string g = "Benchmark";
      o.insert(
          o.end(),
          {opt::frames("frames per run", 100000, "100", g),
           integerOption("--repeat", "R",
                         "runs; stage medians are taken per run, then the median of those", 1, 1000,
                         "3", LP_FIELD(bench.repeat), g),
           textOption("--json", "FILE", "write the results as JSON", LP_FIELD(output.jsonFile), g),
           fileOption("--plot", "FILE.png",
                      "frame times by stage (stacked) and their histogram, drawn by gnuplot",
                      {".png"}, LP_FIELD(output.plot), g),
           textOption("--baseline", "FILE", "JSON from an earlier --json run to compare with",
                      LP_FIELD(bench.baseline), g),
           numberOption("--threshold", "PCT", "allowed slow-down per stage, percent", {0, 1000},
                        "25", LP_FIELD(bench.threshold), g),
           numberOption("--max-contention", "X",
                        "judge stages only while the run's threads waited for a CPU at most X "
                        "times as much as the baseline's did; above, a slower stage is "
                        "inconclusive (exit 2)",
                        {1, 1000}, "1.5", LP_FIELD(bench.maxContention), g),
           injectDelayOption(g), opt::size("render size", 16384, "640x360", g),
           choiceOption("--projection",
                        "where the frame is projected: on the GPU (the frame uploaded, a compute "
                        "pass), on the CPU, or auto: the GPU where the context is a GPU with "
                        "compute shaders",
                        {"auto", "cpu", "gpu"}, "auto", LP_FIELD(bench.projection), g,
                        [](const std::string& v) {
                          return v == "cpu"   ? ProjectOn::Cpu
                                 : v == "gpu" ? ProjectOn::Gpu
                                              : ProjectOn::Auto;
                        }),
           threadsOption(g), sceneOptions()[0], quietOption(g)});
      const auto gl = glOptions(g);
      o.insert(o.end(), gl.begin(), gl.end());
      return o;
    }(),
    0,
    1,
    LP_SOURCE_KINDS "; default: the bundled recording"};

namespace {

/// A stage's median below this (ms) is too small to judge by percent on this machine.
constexpr double kMeasurableMs = 0.05;

std::string plural(long n, const char* word) {
  return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
}

}  // namespace

namespace {

using BenchTimes = std::array<double, kBenchStageCount>;  // by position in kBenchStages

/// What the bench draws into, made once for every run.
struct BenchScene {
  Viewer viewer;  ///< headless: the context, the renderer with the model, the one draw
  LayoutSpec layout;
  glm::mat3 orientation;
  std::array<double, kBenchStageCount> inject{};
  bool gpuProjection = false;  ///< --projection, as decided for the context that came up
  Photometry photometry;       // as the pipeline: one lookup table, each frame's exposure scales it
  /// GPU time of the upload, the projection and the render, by timer queries read three frames
  /// late: every frame's, by stage, as they came back.
  std::unique_ptr<gl::GpuTimer> timer;
  std::array<std::vector<double>, gl::GpuTimer::kStages> gpuTimes;
};

/// Times a frame's GL work of one stage on the GPU.
template <class F>
void onGpuTimer(BenchScene& scene, gl::GpuTimer::Stage stage, F work) {
  scene.timer->begin(stage);
  work();
  scene.timer->end();
}

/// What one run keeps from frame to frame.
struct RunState {
  explicit RunState(const BenchScene& scene)
      : processor({scene.layout, scene.photometry, scene.orientation, 1, {.maxLights = 0}}) {}
  std::shared_ptr<Frame> frame = std::make_shared<Frame>();   ///< the background shares it
  std::shared_ptr<Image> linear = std::make_shared<Image>();  ///< its linear copy, reused
  FrameProcessor processor;  ///< the frame path every command shares
  float exposure = 1.0f;     ///< from the first frame's irradiance
  Sh9 last;                  ///< the last frame's coefficients (in the report)
  // --projection gpu: the frame as the projection reads it, uploaded, and the compute passes.
  gl::FrameTexture gpuFrame;
  std::unique_ptr<gl::GpuProjector> gpu;
};

/// The projection on the GPU: view() of the frame uploaded (8-bit codes as they are), the two
/// compute passes, the coefficients read back, then scaled and turned as on the CPU.
Sh9 projectOnGpu(RunState& run, const LayoutSpec& layout) {
  const FrameProcessor::ProjectedView v = run.processor.view(*run.frame);
  if (!run.gpu || run.gpuFrame.width() != v.view.width || run.gpuFrame.height() != v.view.height)
    run.gpu = std::make_unique<gl::GpuProjector>(layout, v.view.width, v.view.height);
  run.gpuFrame.upload(v.view);
  const Sh9 whole =
      run.gpu->project(run.gpuFrame, v.view.decode, v.view.format == PanoramaFormat::BgrU8);
  return run.processor.fromProjected(whole, v.scale).radiance;
}

/// One frame through the pipeline, stage by stage, as the replay pipeline does it: grab, then
/// the frame path (FrameProcessor::run: convert, only where the display cannot take the frame as
/// it is; project, on the CPU or the GPU; resample, for a layout GL does not draw as it is), then
/// upload, render and read back. One StageClock times them all.
BenchTimes timeFrame(BenchScene& scene, RunState& run, FrameSource& source,
                     const std::string& sourceName, Executor& pool, bool first) {
  StageClock clock;
  const auto injected = [&](Stage stage) {  // --inject-delay's busy work, in its stage
    for (int k = 0; k < kBenchStageCount; ++k)
      if (kBenchStages[std::size_t(k)] == stage) spin(scene.inject[std::size_t(k)]);
  };
  const auto lap = [&](Stage stage) {
    injected(stage);
    clock.lap(stage);
  };
  Frame& frame = *run.frame;
  if (!source.next(frame) && (!source.rewind() || !source.next(frame)))
    throw Error(sourceName + ": no frames to benchmark");
  lap(Stage::Grab);
  scene.timer->beginFrame();
  for (int k = 0; k < gl::GpuTimer::kStages; ++k)
    if (auto ms = scene.timer->justRead(gl::GpuTimer::Stage(k)))
      scene.gpuTimes[std::size_t(k)].push_back(*ms);
  Sh9 sh;
  FrameResult r;
  try {
    r = run.processor.run(
        run.frame, {.background = true, .project = !scene.gpuProjection, .linearInto = run.linear},
        &pool);
    clock.skip();  // (timed by run() itself)
    clock.times += r.times;
    if (scene.gpuProjection) {
      onGpuTimer(scene, gl::GpuTimer::Project, [&] { sh = projectOnGpu(run, scene.layout); });
      clock.lap(Stage::Project);
    } else {
      sh = r.lighting.radiance;
    }
  } catch (const Error& e) {
    throw Error(sourceName + ": " + e.what());
  }
  for (const Stage stage : {Stage::Convert, Stage::Project, Stage::Resample}) lap(stage);
  run.last = sh;
  if (first) run.exposure = autoExposure(sh);
  gl::Renderer& renderer = *scene.viewer.renderer;
  renderer.setLighting(sh);
  onGpuTimer(scene, gl::GpuTimer::Upload, [&] { setBackground(renderer, r.background); });
  gl::Renderer::finish();
  lap(Stage::Upload);
  scene.viewer.state.shading.exposure = run.exposure;
  onGpuTimer(scene, gl::GpuTimer::Render, [&] { scene.viewer.draw(0.0); });
  gl::Renderer::finish();
  lap(Stage::Render);
  auto px = gl::Renderer::readRgb8(scene.viewer.ctx->framebufferSize());
  lap(Stage::Readback);
  BenchTimes t{};
  for (int k = 0; k < kBenchStageCount; ++k)
    t[std::size_t(k)] = clock.times[kBenchStages[std::size_t(k)]];
  return t;
}

/// Per stage: the median of the runs' medians, and p95, p99 and max over every frame; printed
/// as a table and returned as the report's "stages".
nlohmann::ordered_json stageSummary(
    const std::vector<BenchTimes>& all,
    const std::array<std::vector<double>, kBenchStageCount>& runMedians, int repeat, int frames,
    const std::string& description) {
  nlohmann::ordered_json stages;
  std::printf("%-9s %9s %9s %9s %9s   (ms; %s of %s, %s)\n", "stage", "median", "p95", "p99", "max",
              plural(repeat, "run").c_str(), plural(frames, "frame").c_str(), description.c_str());
  for (int s = 0; s < kBenchStageCount; ++s) {
    std::vector<double> v;
    for (const auto& t : all) v.push_back(t[std::size_t(s)]);
    const double med = percentile(runMedians[std::size_t(s)], 0.5);
    stages[stageLabel(s)] = {{"median_ms", med},
                             {"p95_ms", percentile(v, 0.95)},
                             {"p99_ms", percentile(v, 0.99)},
                             {"max_ms", percentile(v, 1.0)}};
    std::printf("%-9s %9.3f %9.3f %9.3f %9.3f\n", stageLabel(s), med, percentile(v, 0.95),
                percentile(v, 0.99), percentile(v, 1.0));
  }
  return stages;
}

/// The GPU's time per stage (timer queries): medians over every frame that came back, printed
/// and returned; {"timer": false} where the context has no GPU timer (a software rasterizer).
nlohmann::ordered_json gpuSummary(const BenchScene& scene) {
  nlohmann::ordered_json g;
  if (!scene.timer->hasTimer()) {
    std::printf("GPU time: no GPU timer (%s)\n", scene.viewer.ctx->describe().c_str());
    g["timer"] = false;
    return g;
  }
  g["timer"] = true;
  std::string line;
  for (int k = 0; k < gl::GpuTimer::kStages; ++k) {
    const auto& v = scene.gpuTimes[std::size_t(k)];
    if (v.empty()) continue;
    const double med = percentile(v, 0.5);
    g[gl::GpuTimer::kNames[k]] = {{"median_ms", med}, {"frames", v.size()}};
    char b[96];
    std::snprintf(b, sizeof b, "%s%s %.3f ms", line.empty() ? "" : ", ", gl::GpuTimer::kNames[k],
                  med);
    line += b;
  }
  std::printf("GPU time (medians, timer queries): %s\n", line.empty() ? "none read" : line.c_str());
  return g;
}

/// The GPU stages against the baseline's, where both have a GPU timer: as measured (a GPU's time
/// does not follow the CPU's calibration kernel), the same thresholds.
void compareGpu(const nlohmann::ordered_json& gpu, const nlohmann::json& baseline, double threshold,
                nlohmann::ordered_json& regressions, int& compared) {
  if (!gpu.value("timer", false) || !baseline.contains("gpu") ||
      !baseline["gpu"].value("timer", false))
    return;
  for (const char* name : gl::GpuTimer::kNames) {
    if (!gpu.contains(name) || !baseline["gpu"].contains(name)) continue;
    const double now = gpu[name]["median_ms"].get<double>();
    const double base = baseline["gpu"][name]["median_ms"].get<double>();
    const double change = base > 0 ? 100.0 * (now - base) / base : 0.0;
    ++compared;
    std::printf("%-11s %8.3f ms vs %.3f ms  %+7.1f%% (GPU time)\n", name, now, base, change);
    if (now - base > 0.5 && change > threshold)
      regressions.push_back({{"stage", name},
                             {"change_pct", change},
                             {"change_ms", now - base},
                             {"median_ms", now},
                             {"baseline_median_ms", base}});
  }
}

/// Each stage against the baseline, both normalised by their calibration kernels and expressed
/// at the baseline's speed. A stage slower than the threshold allows is a regression, unless the
/// run's contention (`load`: this run's factor over the baseline's) explains it: `load` is over
/// `maxLoad` (on a busy machine a short stage waits whole time slices: 0.1 ms of projection read
/// 8 ms beside six stress-ng workers on two cores), or the stage is slower by no more than `load`
/// times what the threshold allows. Those are `inconclusive`.
struct Comparison {
  nlohmann::ordered_json regressions = nlohmann::ordered_json::array();
  nlohmann::ordered_json inconclusive = nlohmann::ordered_json::array();
  int compared = 0;  ///< stages compared
};

Comparison compareWithBaseline(const nlohmann::ordered_json& stages, double calibration,
                               const nlohmann::json& baseline, double threshold, double load,
                               double maxLoad) {
  Comparison c;
  const double baseCal = baseline.at("calibration_ms").get<double>();
  const nlohmann::json& baseStages = baseline.at("stages");
  for (int s = 0; s < kBenchStageCount; ++s) {
    if (!baseStages.contains(stageLabel(s))) continue;
    const double baseMs = baseStages.at(stageLabel(s)).at("median_ms").get<double>();
    const double nowMs = stages[stageLabel(s)]["median_ms"].get<double>();
    const double nowAtBase = nowMs / calibration * baseCal;
    ++c.compared;
    if (baseMs < kMeasurableMs && nowAtBase < kMeasurableMs) {
      std::printf("%-9s %8.3f ms vs %.3f ms (too small to measure)\n", stageLabel(s), nowAtBase,
                  baseMs);
      continue;
    }
    const double change = baseMs > kMeasurableMs ? 100.0 * (nowAtBase - baseMs) / baseMs : 0.0;
    if (baseMs > kMeasurableMs)
      std::printf("%-9s %8.3f ms vs %.3f ms  %+7.1f%% (normalised by calibration)\n", stageLabel(s),
                  nowAtBase, baseMs, change);
    else
      std::printf("%-9s %8.3f ms vs %.3f ms (baseline too small for a percentage)\n", stageLabel(s),
                  nowAtBase, baseMs);
    // A change under 0.5 ms is within scheduling noise on a 2-core machine whatever its
    // percentage.
    if (nowAtBase - baseMs > 0.5 && (baseMs <= kMeasurableMs || change > threshold)) {
      const bool explained =
          load > maxLoad || (load > 1.0 && nowAtBase <= std::max(baseMs, kMeasurableMs) * load *
                                                            (1 + threshold / 100));
      (explained ? c.inconclusive : c.regressions)
          .push_back({{"stage", stageLabel(s)},
                      {"change_pct", change},
                      {"change_ms", nowAtBase - baseMs},
                      {"median_ms", nowMs},
                      {"baseline_median_ms", baseMs}});
    }
  }
  return c;
}

std::string listChanges(const nlohmann::ordered_json& stages) {
  std::string text;
  for (const auto& r : stages) {
    char b[160];
    std::snprintf(b, sizeof b, "%s%s +%.2f ms (%+.1f%%)", text.empty() ? "" : ", ",
                  r["stage"].get<std::string>().c_str(), r["change_ms"].get<double>(),
                  r["change_pct"].get<double>());
    text += b;
  }
  return text;
}

/// The verdict line; returns the exit status (0, 1 a regression, 2 inconclusive).
int printVerdict(const Comparison& c, double threshold, double load) {
  if (!c.regressions.empty()) {
    std::printf("verdict: REGRESSION: %s (threshold %.0f%% and 0.5 ms)\n",
                listChanges(c.regressions).c_str(), threshold);
    return 1;
  }
  if (!c.inconclusive.empty()) {
    std::printf(
        "verdict: inconclusive: slower than the threshold (%.0f%%) allows: %s; but the run waited "
        "for a CPU x%.2f as much as the baseline's did: run it again with nothing else running\n",
        threshold, listChanges(c.inconclusive).c_str(), load);
    return kExitInconclusive;
  }
  std::printf("verdict: no regression (%d stages within %.0f%% of the baseline)\n", c.compared,
              threshold);
  return 0;
}

}  // namespace

int runBench(const Args& a) {
  installStopHandlers();
  const std::string sourceName = a.positional().empty() ? defaultRecording() : a.positional()[0];
  const Settings& s = a.settings();
  const int frames = int(s.output.frames.value_or(100)), repeat = s.bench.repeat;
  const double threshold = s.bench.threshold;
  const auto size = s.output.size.value_or(Size{640, 360});
  const unsigned threads = unsigned(s.stream.threads);
  nlohmann::json baseline;
  if (s.bench.baseline)
    baseline = parseBaseline(readInputFile(*s.bench.baseline), *s.bench.baseline);
  layoutSpec(s.panorama);  // option errors before the source is opened
  std::unique_ptr<FrameSource> source = openSource(sourceName);
  // Headless: EGL on a GPU where there is one (the GPU a user ships on), else OSMesa; --gl picks.
  const gl::Backend backend = s.scene.gl == gl::Backend::Auto ? gl::Backend::Headless : s.scene.gl;
  BenchScene scene{Viewer(ViewerSpec{backend, size, {}, false, false, false, true, s.scene.gpu},
                          meshFrom(s.scene)),
                   layoutSpec(s.panorama, source.get()), envOrientation(s.panorama), [&] {
                     std::array<double, kBenchStageCount> inject{};
                     for (const auto& [stage, ms] : s.bench.injectDelay)
                       inject[std::size_t(stage)] += ms;
                     return inject;
                   }()};
  scene.viewer.renderer->setEnvOrientation(scene.orientation);
  scene.timer = std::make_unique<gl::GpuTimer>();
  const std::string glName = scene.viewer.ctx->describe();
  const bool gpuContext = !gl::isSoftwareRenderer(glName) && gl::hasCompute();
  scene.gpuProjection =
      s.bench.projection == ProjectOn::Gpu || (s.bench.projection == ProjectOn::Auto && gpuContext);
  if (scene.gpuProjection && !gl::hasCompute())
    throw Error("--projection gpu: " + glName + " has no compute shaders (GL 4.3)");
  ThreadPool pool(threads);

  // The runs: each starts the source from its first frame (rewound, or opened again where it
  // cannot rewind) and times every frame; the calibration kernel is timed before each frame.
  std::vector<BenchTimes> all;
  std::array<std::vector<double>, kBenchStageCount> runMedians;
  {
    // A source that gives no frame (a corrupt file) is refused before the calibration's
    // repetitions: at once, not seconds later (minutes in a sanitizer build).
    Frame first;
    if (!source->next(first)) throw Error(sourceName + ": no frames to benchmark");
    if (!source->rewind()) source = openSource(sourceName);
  }
  CalibrationKernel calibrationKernel;
  std::string description;
  const Contention sched;
  std::array<Rgb, kShCount> lastCoefficients{};
  Progress progress("bench", std::int64_t(frames) * repeat, s.output.quiet);
  for (int run = 0; run < repeat && !stopRequested(); ++run) {
    for (int i = 0; i < 21; ++i) calibrationKernel.time();
    if (run > 0 && !source->rewind()) source = openSource(sourceName);
    description = source->describe();
    RunState state(scene);
    std::vector<BenchTimes> times;
    for (int i = 0; i < frames && !stopRequested(); ++i) {
      calibrationKernel.time();
      times.push_back(timeFrame(scene, state, *source, sourceName, pool, i == 0));
      progress.update(std::int64_t(all.size() + times.size()));
    }
    lastCoefficients = state.last.c;
    if (times.empty()) break;
    for (int s = 0; s < kBenchStageCount; ++s) {
      std::vector<double> v;
      for (const auto& t : times) v.push_back(t[std::size_t(s)]);
      runMedians[std::size_t(s)].push_back(percentile(v, 0.5));
    }
    all.insert(all.end(), times.begin(), times.end());
  }
  progress.finish();
  if (stopRequested()) {
    std::fprintf(stderr, "liveprobe: bench stopped by a signal after %s; nothing written\n",
                 plural(long(all.size()), "frame").c_str());
    return kExitInterrupted;
  }

  // The report: stages, calibration, the comparison, then the files and the verdict.
  const double calibration = calibrationKernel.speed(), contention = sched.factor();
  nlohmann::ordered_json out;
  out["frames"] = frames;
  out["runs"] = repeat;
  out["source"] = description;
  // Which GL drew and where the projection ran, before the table (after the runs, so that a
  // source that fails is still one line).
  std::printf("drawn with %s; projection on the %s\n", glName.c_str(),
              scene.gpuProjection ? "GPU" : "CPU");
  out["stages"] = stageSummary(all, runMedians, repeat, frames, description);
  // Latency, as replay measures it: from the frame's grab to the frame shown (read back).
  std::vector<double> latency;
  for (const auto& t : all) latency.push_back(std::accumulate(t.begin() + 1, t.end(), 0.0));
  out["latency_ms"] = {{"p50", percentile(latency, 0.5)},
                       {"p95", percentile(latency, 0.95)},
                       {"p99", percentile(latency, 0.99)}};
  std::printf("latency (grab to shown) ms: p50 %.2f, p95 %.2f, p99 %.2f\n",
              percentile(latency, 0.5), percentile(latency, 0.95), percentile(latency, 0.99));
  out["calibration_ms"] = calibration;
  std::printf("calibration kernel: %.3f ms\n", calibration);
  out["contention"] = contention;
  std::printf("contention: x%.2f (the run's threads waited for a CPU %.0f%% as long as they ran)\n",
              contention, 100 * (contention - 1));
  out["gl"] = glName;
  out["projection"] = scene.gpuProjection ? "gpu" : "cpu";
  out["gpu"] = gpuSummary(scene);
  nlohmann::ordered_json last = nlohmann::ordered_json::array();
  for (const Rgb& c : lastCoefficients) last.push_back({c.x, c.y, c.z});
  out["last_coefficients"] = last;
  // Contention relative to the baseline's (a baseline taken under the same load explains it).
  const double load =
      contention / std::max(1.0, baseline.is_null() ? 1.0 : baseline.value("contention", 1.0));
  Comparison comparison;
  if (!baseline.is_null()) {
    comparison = compareWithBaseline(out["stages"], calibration, baseline, threshold, load,
                                     s.bench.maxContention);
    compareGpu(out["gpu"], baseline, threshold, comparison.regressions, comparison.compared);
  }
  out["regressions"] = comparison.regressions;
  out["inconclusive"] = comparison.inconclusive;
  if (s.output.jsonFile) writeFileAtomically(*s.output.jsonFile, out.dump(2) + "\n");
  if (s.output.plot)
    drawPlot(*s.output.plot, all, frames,
             "liveprobe bench: " + description + " (" + plural(repeat, "run") + " of " +
                 plural(frames, "frame") + ")");
  return baseline.is_null() ? 0 : printVerdict(comparison, threshold, load);
}

}  // namespace lp::cli
