// liveprobe bench: a frame-time regression run of the whole replay pipeline, headless.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <thread>

#include <opencv2/imgproc.hpp>

#include "capture/error.h"
#include "capture/frame.h"
#include "capture/layout.h"
#include "capture/photometry.h"
#include "capture/pipeline.h"
#include "coeffs_io.h"
#include "commands.h"
#include "scene.h"
#include "shading/thread_pool.h"

namespace lp::cli {

namespace {

using Clock = std::chrono::steady_clock;
const char* const kStages[] = {"grab", "convert", "project", "upload", "render", "readback"};
constexpr int kStageCount = 6;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double pos = p * double(v.size() - 1);
  const auto i = std::size_t(pos);
  const double f = pos - double(i);
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

// Busy-waits, so an injected delay costs CPU time like real work does.
void spin(double ms) {
  const auto end = Clock::now() + std::chrono::duration<double, std::milli>(ms);
  while (Clock::now() < end) {
  }
}

// The calibration kernel: a fixed amount of the machine's own kind of work (projecting a fixed
// synthetic frame, single thread), timed in the same run. Stage times are divided by it, so a
// slower or busier machine is not a regression.
double calibrationMs() {
  static std::vector<float> sky;
  if (sky.empty()) renderSyntheticSky(512, 256, 0.5, sky);
  const EquirectProjector proj(512, 256);
  std::vector<double> t;
  for (int i = 0; i < 21; ++i) {
    const auto t0 = Clock::now();
    Sh9 s;
    for (int r = 0; r < 10; ++r) s += proj.project(sky.data(), 512 * 3);
    volatile float sink = s.c[0].x;
    (void)sink;
    t.push_back(msSince(t0));
  }
  return percentile(t, 0.5);
}

void drawPlot(const std::string& path, const std::vector<std::array<double, kStageCount>>& frames) {
  const int W = 900, H = 360, histW = 300, pad = 40;
  cv::Mat img(H, W + histW, CV_8UC3, cv::Scalar(255, 255, 255));
  std::vector<double> total;
  for (const auto& f : frames) {
    double s = 0;
    for (double v : f) s += v;
    total.push_back(s);
  }
  const double ymax = std::max(1e-3, percentile(total, 1.0) * 1.1);
  const cv::Scalar colours[kStageCount] = {{180, 119, 31}, {14, 127, 255}, {44, 160, 44}, {40, 39, 214}, {189, 103, 148}, {75, 86, 140}};
  auto X = [&](std::size_t i) { return pad + int((W - 2 * pad) * double(i) / std::max<std::size_t>(1, frames.size() - 1)); };
  auto Y = [&](double ms) { return H - pad - int((H - 2 * pad) * ms / ymax); };
  // Stacked stages: each line is the cumulative time up to that stage.
  for (int s = kStageCount - 1; s >= 0; --s)
    for (std::size_t i = 1; i < frames.size(); ++i) {
      double a = 0, b = 0;
      for (int k = 0; k <= s; ++k) a += frames[i - 1][k], b += frames[i][k];
      cv::line(img, {X(i - 1), Y(a)}, {X(i), Y(b)}, colours[s], 1, cv::LINE_AA);
    }
  cv::rectangle(img, {pad, pad}, {W - pad, H - pad}, cv::Scalar(0, 0, 0));
  char label[64];
  std::snprintf(label, sizeof label, "%.1f ms", ymax);
  cv::putText(img, label, {4, pad + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.4, {0, 0, 0});
  cv::putText(img, "0", {pad - 14, H - pad}, cv::FONT_HERSHEY_SIMPLEX, 0.4, {0, 0, 0});
  cv::putText(img, "frame time (cumulative by stage) vs frame number", {pad, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0});
  for (int s = 0; s < kStageCount; ++s)
    cv::putText(img, kStages[s], {pad + 90 * s, H - 10}, cv::FONT_HERSHEY_SIMPLEX, 0.45, colours[s], 1, cv::LINE_AA);
  // Histogram of total frame time.
  const int bins = 30;
  std::vector<int> h(bins, 0);
  for (double t : total) h[std::min(bins - 1, int(bins * t / ymax))]++;
  const int hmax = std::max(1, *std::max_element(h.begin(), h.end()));
  const int x0 = W + 10, bw = (histW - 30) / bins;
  for (int b = 0; b < bins; ++b) {
    const int top = H - pad - (H - 2 * pad) * h[b] / hmax;
    cv::rectangle(img, {x0 + b * bw, top}, {x0 + (b + 1) * bw - 1, H - pad}, {120, 120, 120}, cv::FILLED);
  }
  cv::putText(img, "histogram of frame time", {x0, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0});
  std::snprintf(label, sizeof label, "0 .. %.1f ms", ymax);
  cv::putText(img, label, {x0, H - 10}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0});
  saveImage8(path, img.cols, img.rows, 3, img.ptr<std::uint8_t>());
}

}  // namespace

const CommandSpec kBenchSpec{
    "bench",
    "[SOURCE] [--frames N] [--repeat R] [--json OUT] [--plot OUT.png] [--baseline FILE]\n"
    "       [--threshold PCT] [--inject-delay STAGE=MS] [--size WxH] [--model FILE|sphere]",
    "Frame-time regression run: replays N frames headless through the whole pipeline (R times)\n"
    "and times each stage per frame: grab (decode), convert, project, upload, render, readback.\n"
    "Reports median, p95, p99 and max per stage. With --baseline it compares the medians of the\n"
    "runs, divided by a calibration kernel timed in the same run, and exits 1 when a stage is\n"
    "slower than the baseline by more than --threshold percent (default 25). --inject-delay\n"
    "slows one stage on purpose, to prove the detector works.",
    [] {
      auto o = layoutOptions();
      o.insert(o.end(), {{"--frames", "N", "frames per run (default 100)"},
                         {"--repeat", "R", "runs; stage medians are taken per run, then the median of those (default 3)"},
                         {"--json", "FILE", "write the results as JSON"},
                         {"--plot", "FILE.png", "frame time against frame number, and a histogram"},
                         {"--baseline", "FILE", "JSON from an earlier --json run to compare with"},
                         {"--threshold", "PCT", "allowed slow-down per stage, percent (default 25)"},
                         {"--inject-delay", "STAGE=MS", "add MS milliseconds of busy work to STAGE", true},
                         {"--size", "WxH", "render size (default 640x360)"},
                         {"--threads", "N", "projection threads (default 2)"},
                         {"--model", "FILE|sphere", "model (default sphere)"}});
      return o;
    }(),
    0, 1};

int runBench(const Args& a) {
  const std::string sourceName = a.positional().empty() ? defaultRecording() : a.positional()[0];
  const int frames = a.integer("--frames", 100), repeat = a.integer("--repeat", 3);
  if (frames < 1 || repeat < 1) throw Error("bench: --frames and --repeat must be at least 1");
  const double threshold = a.number("--threshold", 25.0);
  const auto size = parseSize(a.get("--size", "640x360"), "--size");
  const unsigned threads = unsigned(std::max(1, a.integer("--threads", 2)));
  std::array<double, kStageCount> inject{};
  for (const auto& d : a.all("--inject-delay")) {
    const auto eq = d.find('=');
    int stage = -1;
    for (int s = 0; s < kStageCount; ++s)
      if (eq != std::string::npos && d.substr(0, eq) == kStages[s]) stage = s;
    if (stage < 0) throw Error("--inject-delay " + d + ": expected STAGE=MS, STAGE one of grab convert project upload render readback");
    inject[stage] += parseNumber(d.substr(eq + 1), "--inject-delay");
  }
  nlohmann::json baseline;
  if (a.has("--baseline")) {
    std::ifstream in(a.get("--baseline"));
    if (!in) throw Error(a.get("--baseline") + ": cannot open the baseline");
    try {
      in >> baseline;
      (void)baseline.at("stages");
      (void)baseline.at("calibration_ms").get<double>();
    } catch (const std::exception& e) {
      throw Error(a.get("--baseline") + ": not a liveprobe bench JSON (" + e.what() + ")");
    }
  }
  const LayoutSpec layout = layoutFromArgs(a);
  const Mesh mesh = meshFromArgs(a);
  auto ctx = openContext(gl::Backend::Headless, size);
  gl::Renderer renderer;
  loadModel(renderer, mesh);
  ThreadPool pool(threads);
  const Linearizer linearizer;
  std::vector<std::array<double, kStageCount>> all;
  std::array<std::vector<double>, kStageCount> runMedians;
  std::vector<double> calibrations;
  std::string description;
  for (int run = 0; run < repeat; ++run) {
    calibrations.push_back(calibrationMs());
    auto source = openSource(sourceName);
    description = source->describe();
    Photometry photometry;
    photometry.exposure = float(source->radianceScale());
    const Linearizer lin(photometry);
    std::optional<Projector> projector;
    std::vector<std::array<double, kStageCount>> times;
    Frame frame;
    Image image;
    float exposure = 1.0f;
    for (int i = 0; i < frames; ++i) {
      std::array<double, kStageCount> t{};
      auto t0 = Clock::now();
      if (!source->next(frame)) {
        if (!source->rewind() || !source->next(frame)) throw Error(sourceName + ": no frames to benchmark");
      }
      spin(inject[0]);
      t[0] = msSince(t0);
      t0 = Clock::now();
      // As the replay pipeline does: only frames the display cannot take as they are get a
      // linear copy.
      const bool asIs = displayTakesFrameAsIs(frame, photometry, layout);
      if (!asIs) lin.convert(frame, image);
      spin(inject[1]);
      t[1] = msSince(t0);
      t0 = Clock::now();
      if (!projector || projector->width() != frame.width || projector->height() != frame.height) {
        if (auto why = layoutMismatch(layout, frame.width, frame.height); !why.empty()) throw Error(sourceName + ": " + why);
        projector.emplace(layout, frame.width, frame.height);
      }
      const Sh9 sh = projectFrame(*projector, frame, lin, &pool);
      spin(inject[2]);
      t[2] = msSince(t0);
      t0 = Clock::now();
      if (i == 0) exposure = autoExposure(sh);
      renderer.setLighting(sh);
      if (asIs) setBackground(renderer, frame, layout, lin.exposure());
      else setBackground(renderer, image, layout);
      gl::Renderer::finish();
      spin(inject[3]);
      t[3] = msSince(t0);
      t0 = Clock::now();
      gl::ShadingSettings shading;
      shading.exposure = exposure;
      renderer.draw(ctx->framebufferSize(), gl::Camera{}, shading);
      gl::Renderer::finish();
      spin(inject[4]);
      t[4] = msSince(t0);
      t0 = Clock::now();
      auto px = gl::Renderer::readRgb8(ctx->framebufferSize());
      spin(inject[5]);
      t[5] = msSince(t0);
      times.push_back(t);
    }
    for (int s = 0; s < kStageCount; ++s) {
      std::vector<double> v;
      for (const auto& t : times) v.push_back(t[s]);
      runMedians[s].push_back(percentile(v, 0.5));
    }
    all.insert(all.end(), times.begin(), times.end());
  }
  const double calibration = percentile(calibrations, 0.5);

  nlohmann::ordered_json out;
  out["frames"] = frames;
  out["runs"] = repeat;
  out["source"] = description;
  nlohmann::ordered_json stages;
  std::printf("%-9s %9s %9s %9s %9s   (ms; %d runs of %d frames, %s)\n", "stage", "median", "p95", "p99", "max",
              repeat, frames, description.c_str());
  for (int s = 0; s < kStageCount; ++s) {
    std::vector<double> v;
    for (const auto& t : all) v.push_back(t[s]);
    const double med = percentile(runMedians[s], 0.5);
    stages[kStages[s]] = {{"median_ms", med}, {"p95_ms", percentile(v, 0.95)}, {"p99_ms", percentile(v, 0.99)},
                          {"max_ms", percentile(v, 1.0)}};
    std::printf("%-9s %9.3f %9.3f %9.3f %9.3f\n", kStages[s], med, percentile(v, 0.95), percentile(v, 0.99),
                percentile(v, 1.0));
  }
  out["stages"] = stages;
  out["calibration_ms"] = calibration;
  std::printf("calibration kernel: %.3f ms\n", calibration);
  nlohmann::ordered_json regressions = nlohmann::ordered_json::array();
  if (!baseline.is_null()) {
    const double baseCal = baseline["calibration_ms"].get<double>();
    for (int s = 0; s < kStageCount; ++s) {
      if (!baseline["stages"].contains(kStages[s])) continue;
      const double base = baseline["stages"][kStages[s]]["median_ms"].get<double>() / baseCal;
      const double now = stages[kStages[s]]["median_ms"].get<double>() / calibration;
      // A change under 0.5 ms (at the baseline's speed) is within scheduling noise on a 2-core
      // machine whatever its percentage: sub-millisecond stages are judged by percent only above it.
      const double floorMs = 0.5 / baseCal;
      const double change = base > 0 ? 100.0 * (now - base) / base : 0.0;
      std::printf("%-9s %+7.1f%% against the baseline (normalised by calibration)\n", kStages[s], change);
      if (change > threshold && now - base > floorMs)
        regressions.push_back({{"stage", kStages[s]}, {"change_pct", change},
                               {"median_ms", stages[kStages[s]]["median_ms"]},
                               {"baseline_median_ms", baseline["stages"][kStages[s]]["median_ms"]}});
    }
  }
  out["regressions"] = regressions;
  if (a.has("--json")) {
    const std::string path = a.get("--json"), tmp = path + ".tmp";
    std::ofstream f(tmp);
    f << out.dump(2) << "\n";
    f.close();
    if (!f || std::rename(tmp.c_str(), path.c_str()) != 0) throw Error(path + ": cannot write");
  }
  if (a.has("--plot")) drawPlot(a.get("--plot"), all);
  for (const auto& r : regressions)
    std::printf("REGRESSION: %s is %.1f%% slower than the baseline (threshold %.0f%%)\n",
                r["stage"].get<std::string>().c_str(), r["change_pct"].get<double>(), threshold);
  return regressions.empty() ? 0 : 1;
}

}  // namespace lp::cli
