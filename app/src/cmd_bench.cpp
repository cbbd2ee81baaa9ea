// liveprobe bench: a frame-time regression run of the whole replay pipeline, headless.

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench_frame.h"
#include "commands.h"
#include "environment.h"
#include "liveprobe/bench/plot.h"
#include "liveprobe/bench/verdict.h"
#include "liveprobe/capture/atomic_file.h"
#include "liveprobe/capture/open_source.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/frame/input_file.h"
#include "liveprobe/gl/gpu_timer.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/executor.h"
#include "progress.h"
#include "scene.h"
#include "scene_gl.h"
#include "viewer.h"

namespace lp::cli {

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
      if (eq != std::string::npos && d.substr(0, eq) == benchStageName(k)) stage = k;
    if (stage < 0) {
      std::string names;
      for (int k = 0; k < kBenchStageCount; ++k) names += std::string(" ") + benchStageName(k);
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
           injectDelayOption(g), opt::size("render size", 16384, "640x360", g), threadsOption(g),
           sceneOptions()[0], quietOption(g)});
      const auto gl = glOptions(g);
      o.insert(o.end(), gl.begin(), gl.end());
      return o;
    }(),
    0,
    1,
    LP_SOURCE_KINDS "; default: the bundled recording"};

namespace {

std::string plural(long n, const char* word) {
  return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
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
    baseline = bench::parseBaseline(readInputFile(*s.bench.baseline), *s.bench.baseline);
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
  scene.gpuProjection = projectsOnGpu(s.scene.projection, *scene.viewer.ctx);
  ThreadPool pool(threads);

  {
    // A source that gives no frame (a corrupt file) is refused before the calibration's
    // repetitions: at once, not seconds later (minutes in a sanitizer build).
    Frame first;
    if (!source->next(first)) throw Error(sourceName + ": no frames to benchmark");
    if (!source->rewind()) source = openSource(sourceName);
  }
  // The runs: each starts the source from its first frame (rewound, or opened again where it
  // cannot rewind) and times every frame.
  std::string description;
  std::unique_ptr<RunState> state;
  std::array<Rgb, kShCount> lastCoefficients{};
  Progress progress("bench", std::int64_t(frames) * repeat, s.output.quiet);
  std::vector<std::string> stageNames;
  for (int k = 0; k < kBenchStageCount; ++k) stageNames.push_back(benchStageName(k));
  const bench::Runs runs = bench::measure(
      stageNames, repeat, frames,
      {.startRun =
           [&](int run) {
             if (run > 0 && !source->rewind()) source = openSource(sourceName);
             description = source->describe();
             state = std::make_unique<RunState>(scene);
           },
       .frame =
           [&](int, int i) {
             const BenchTimes t = timeFrame(scene, *state, *source, sourceName, pool, i == 0);
             lastCoefficients = state->last.c;
             return std::vector<double>(t.begin(), t.end());
           },
       .stop = stopRequested,
       .progress = [&](std::int64_t done) { progress.update(done); }});
  progress.finish();
  if (runs.stopped) {
    std::fprintf(stderr, "liveprobe: bench stopped by a signal after %s; nothing written\n",
                 plural(long(runs.frames.size()), "frame").c_str());
    return kExitInterrupted;
  }

  // The report: stages, calibration, the comparison, then the files and the verdict.
  nlohmann::ordered_json out;
  out["frames"] = frames;
  out["runs"] = repeat;
  out["source"] = description;
  // Which GL drew and where the projection ran, before the table (after the runs, so that a
  // source that fails is still one line).
  std::printf("drawn with %s; projection on the %s\n", glName.c_str(),
              scene.gpuProjection ? "GPU" : "CPU");
  const bench::Summary summary = bench::summarize(runs, description);
  for (const std::string& line : summary.lines) std::printf("%s\n", line.c_str());
  out.update(summary.json);
  out["gl"] = glName;
  out["projection"] = scene.gpuProjection ? "gpu" : "cpu";
  out["gpu"] = gpuSummary(scene);
  nlohmann::ordered_json last = nlohmann::ordered_json::array();
  for (const Rgb& c : lastCoefficients) last.push_back({c.x, c.y, c.z});
  out["last_coefficients"] = last;
  // Contention relative to the baseline's (a baseline taken under the same load explains it).
  const double load =
      runs.contention / std::max(1.0, baseline.is_null() ? 1.0 : baseline.value("contention", 1.0));
  bench::Comparison comparison;
  if (!baseline.is_null()) {
    std::vector<std::pair<std::string, double>> medians, gpu;
    for (const auto& [name, st] : out["stages"].items())
      medians.emplace_back(name, st["median_ms"].get<double>());
    for (const char* name : gl::GpuTimer::kNames)
      if (out["gpu"].value("timer", false) && out["gpu"].contains(name))
        gpu.emplace_back(name, out["gpu"][name]["median_ms"].get<double>());
    comparison = bench::compareWithBaseline(medians, runs.calibrationMs, baseline, threshold, load,
                                            s.bench.maxContention);
    bench::compareGpu(gpu, baseline, threshold, comparison);
    for (const std::string& line : comparison.lines) std::printf("%s\n", line.c_str());
  }
  out["regressions"] = comparison.regressions;
  out["inconclusive"] = comparison.inconclusive;
  if (s.output.jsonFile) writeFileAtomically(*s.output.jsonFile, out.dump(2) + "\n");
  if (s.output.plot)
    bench::drawStagePlot(*s.output.plot, runs,
                         "liveprobe bench: " + description + " (" + plural(repeat, "run") + " of " +
                             plural(frames, "frame") + ")");
  if (baseline.is_null()) return 0;
  const auto [verdict, line] = bench::verdict(comparison, threshold, load);
  std::printf("%s\n", line.c_str());
  return verdict == bench::Verdict::Regression     ? 1
         : verdict == bench::Verdict::Inconclusive ? kExitInconclusive
                                                   : 0;
}

}  // namespace lp::cli
