// liveprobe-bench: Google Benchmark suite (run with --benchmark_format=json).
// Names carry layout, pixel type, size and threads: Project/equirect/f32/300x300/threads:1.
// This file is compiled with the same flags as the projection kernels (-O3, reassociation), so
// the plain reference loop below is a fair in-run yardstick.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <numbers>
#include <random>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "../turned_map.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/capture/lens.h"
#include "liveprobe/capture/open_source.h"
#include "liveprobe/capture/photometry.h"
#include "liveprobe/capture/resample.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/gl/mesh.h"
#include "liveprobe/gl/renderer.h"
#include "liveprobe/hdr/merge.h"
#include "liveprobe/sh/brute.h"
#include "liveprobe/sh/executor.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/projector.h"
#include "liveprobe/sh/sh.h"
#include "liveprobe/sh/simd.h"
#include "plain_loop.h"

namespace {

constexpr double kPi = std::numbers::pi;

struct Size {
  int w, h;
};

std::string sizeName(Size s) { return std::to_string(s.w) + "x" + std::to_string(s.h); }

// A natural-looking test frame: the synthetic sky, resized by rendering it at that size.
const std::vector<float>& skyF32(Size s) {
  static std::map<std::pair<int, int>, std::vector<float>> cache;
  auto& v = cache[{s.w, s.h}];
  if (v.empty()) lp::renderSyntheticSky(s.w, s.h, 1.0, v);
  return v;
}

const std::vector<std::uint8_t>& skyU8(Size s) {
  static std::map<std::pair<int, int>, std::vector<std::uint8_t>> cache;
  auto& v = cache[{s.w, s.h}];
  if (v.empty()) {
    const auto& f = skyF32(s);
    v.resize(f.size());
    for (std::size_t i = 0; i < f.size(); i += 3)
      for (int c = 0; c < 3; ++c)
        v[i + 2 - c] = std::uint8_t(std::lround(255 * lp::linearToSrgb(f[i + c] * 0.1f)));
  }
  return v;
}

lp::ThreadPool* pool(int threads) {
  static std::map<int, std::unique_ptr<lp::ThreadPool>> pools;
  auto& p = pools[threads];
  if (!p) p = std::make_unique<lp::ThreadPool>(unsigned(threads));
  return threads > 1 ? p.get() : nullptr;
}

// The tests' fisheye (tests/test_lens.cpp): Kannala-Brandt, 1280x960, 180 degrees; other sizes
// of its aspect are the lens scaled.
lp::LayoutSpec benchLens() {
  lp::LensCalibration c;
  c.model = lp::LensCalibration::Model::Fisheye;
  c.width = 1280, c.height = 960;
  c.K = {285, 0, 641.3, 0, 286.5, 478.6, 0, 0, 1};
  c.distortion = {0.021, -0.0043, 0.0012, -0.00021};
  c.source = "the bench's fisheye";
  lp::LayoutSpec spec(lp::Layout::Lens);
  spec.lens = lp::makeLensModel(c);
  return spec;
}

void projectBench(benchmark::State& state, const lp::LayoutSpec& layout, bool u8, Size s,
                  int threads, const std::string& simd) {
  lp::simd::select(simd);
  struct Restore {  // the other benchmarks run on the best path
    ~Restore() { lp::simd::select("native"); }
  } restore;
  // Everything the projection reads is made before the timed loop (the sky's rendering would
  // otherwise land in the first iteration, which sets the iteration count), and one untimed
  // projection warms the caches and the thread pool.
  lp::Projector proj(layout, s.w, s.h);
  const lp::Linearizer lin;
  const std::uint8_t* bgr = u8 ? skyU8(s).data() : nullptr;
  const float* rgb = u8 ? nullptr : skyF32(s).data();
  lp::ThreadPool* workers = pool(threads);
  const lp::PanoramaView view =
      u8 ? lp::PanoramaView::bgrU8(bgr, s.w, s.h, lin.table().data(), layout)
         : lp::PanoramaView::rgbF32(rgb, s.w, s.h, layout);
  auto run = [&] { return proj.project(view, workers); };
  benchmark::DoNotOptimize(run());
  for (auto _ : state) {
    const lp::Sh9 sh = run();
    benchmark::DoNotOptimize(sh);
  }
  state.counters["ns_per_pixel"] =
      benchmark::Counter(double(s.w) * s.h * 1e-9, benchmark::Counter::kIsIterationInvariantRate |
                                                       benchmark::Counter::kInvert);
}

// Projection alone, and projection with light extraction (the row peaks taken during the
// projection, then the sun's neighbourhood), on the same frame in the same run: the extraction's
// cost budget is the ratio of the two (at most 1.2 at 1920x1080 and 3840x1920). mode 0: projection
// alone; 1: projection plus extraction; 2: the extraction alone, timed after an untimed projection
// of the same frame each iteration (the caches as a frame leaves them).
void lightsBench(benchmark::State& state, bool u8, Size s, int mode) {
  const lp::Projector proj(lp::Layout::Equirect, s.w, s.h);
  const lp::LightExtractor extractor(proj);
  const lp::Linearizer lin;
  const lp::PanoramaView view =
      u8 ? lp::PanoramaView::bgrU8(skyU8(s).data(), s.w, s.h, lin.table().data())
         : lp::PanoramaView::rgbF32(skyF32(s).data(), s.w, s.h);
  std::vector<float> peaks;
  std::size_t lights = 0;
  auto run = [&] {
    if (mode == 0) return proj.project(view, pool(2));
    const lp::Sh9 whole = proj.project(view, pool(2), &peaks);
    const lp::LightSplit split = extractor.extract(view, whole, peaks, {});
    lights = split.lights.size();
    return split.residual;
  };
  benchmark::DoNotOptimize(run());
  if (mode == 2) {
    for (auto _ : state) {
      state.PauseTiming();
      const lp::Sh9 whole = proj.project(view, pool(2), &peaks);
      state.ResumeTiming();
      const lp::LightSplit split = extractor.extract(view, whole, peaks, {});
      benchmark::DoNotOptimize(split);
    }
  } else {
    for (auto _ : state) {
      const lp::Sh9 sh = run();
      benchmark::DoNotOptimize(sh);
    }
  }
  state.counters["lights"] = double(lights);
}

// The plain loop: per-pixel basis from precomputed directions and solid angles, 27 multiply-adds
// per pixel into float accumulators, one thread. What a straightforward implementation does.
void referenceLoop(benchmark::State& state, Size s) {
  const auto samples = lp::layoutSamples(lp::Layout::Equirect, s.w, s.h);
  const auto& rgb = skyF32(s);
  for (auto _ : state) {
    float acc[27] = {};
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const auto y = lp::shBasis(samples[i].dir);
      const float dw = samples[i].solidAngle;
      for (int k = 0; k < 9; ++k) {
        const float w = y[k] * dw;
        acc[3 * k] += w * rgb[3 * i], acc[3 * k + 1] += w * rgb[3 * i + 1],
            acc[3 * k + 2] += w * rgb[3 * i + 2];
      }
    }
    benchmark::DoNotOptimize(acc);
  }
  state.counters["ns_per_pixel"] =
      benchmark::Counter(double(s.w) * s.h * 1e-9, benchmark::Counter::kIsIterationInvariantRate |
                                                       benchmark::Counter::kInvert);
}

// The plain equirect loop of plain_loop.cpp (-march=native -ffast-math, one thread): the
// yardstick the lens layout's projection is held to (at most 2x its time at the same size).
void plainLoop(benchmark::State& state, Size s) {
  const lpbench::PlainEquirect plain(s.w, s.h);
  const auto& rgb = skyF32(s);
  for (auto _ : state) benchmark::DoNotOptimize(plain.project(rgb.data()));
  state.counters["ns_per_pixel"] =
      benchmark::Counter(double(s.w) * s.h * 1e-9, benchmark::Counter::kIsIterationInvariantRate |
                                                       benchmark::Counter::kInvert);
}

// Brute force at T = 64x64 output texels on the 300x300 map, with the SH time (projection plus
// evaluation at the same T normals) measured in the same run, and their ratio.
void bruteBench(benchmark::State& state, int threads) {
  const Size s{300, 300};
  const auto samples = lp::layoutSamples(lp::Layout::Equirect, s.w, s.h);
  const auto grid = lp::equirectSamples(64, 64);
  std::vector<glm::vec3> normals;
  for (const auto& g : grid) normals.push_back(g.dir);
  const auto& rgb = skyF32(s);
  const lp::Projector proj(lp::Layout::Equirect, s.w, s.h);
  double shSeconds = 1e30;
  for (int rep = 0; rep < 50; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto m =
        lp::irradianceMatrices(proj.project(lp::PanoramaView::rgbF32(rgb.data(), s.w, s.h)));
    glm::vec3 sum(0);
    for (const auto& n : normals) sum += lp::evalIrradianceQuadratic(m, n);
    benchmark::DoNotOptimize(sum);
    shSeconds = std::min(
        shSeconds, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  double bruteSeconds = 0;
  int n = 0;
  lp::ThreadPool workers{unsigned(threads)};
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    auto e = lp::bruteIrradiance(rgb.data(), 3, samples.data(), samples.size(), normals, &workers);
    benchmark::DoNotOptimize(e);
    bruteSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ++n;
  }
  state.counters["sh_us"] = shSeconds * 1e6;
  state.counters["ratio_brute_over_sh"] = bruteSeconds / n / shSeconds;
  state.counters["paper_ratio_T_over_9"] = 64.0 * 64.0 / 9.0;
}

// A GL frame of the bunny at 1280x720 on OSMesa: draw + readback.
void renderBench(benchmark::State& state) {
  static auto ctx = lp::gl::createGlContext({lp::gl::Backend::Headless, 1280, 720, "bench", false});
  lp::gl::Renderer r;
  lp::Mesh mesh = lp::loadMesh(std::string(LIVEPROBE_DATA_DIR) + "/models/stanford-bunny.obj");
  lp::fitToUnitSphere(mesh);
  r.setMesh(mesh);
  const Size s{512, 256};
  r.setLighting(lp::project(lp::PanoramaView::rgbF32(skyF32(s).data(), s.w, s.h)));
  r.setBackground(skyF32(s).data(), s.w, s.h, lp::gl::BackgroundMapping::Equirect);
  for (auto _ : state) {
    r.draw({1280, 720}, lp::gl::Camera{}, lp::gl::ShadingSettings{});
    auto px = lp::gl::Renderer::readRgb8({1280, 720});
    benchmark::DoNotOptimize(px);
  }
}

// The two floors of a projection, measured in the same run on the same threads. They use AVX2
// and FMA explicitly (this file is built for the x86-64 baseline, where a plain loop would be
// SSE2 with one accumulator, and std::fma a library call), with enough independent accumulators
// to hide latency.
#if defined(__x86_64__)
#define LP_FLOOR_TARGET __attribute__((target("avx2,fma")))
#else
#define LP_FLOOR_TARGET
#endif

// Reading: the frame's bytes summed, split into the same row bands across the threads.
LP_FLOOR_TARGET double readSum(const void* data, std::size_t bytes, bool u8) {
#if defined(__x86_64__)
  const auto* p = static_cast<const std::uint8_t*>(data);
  std::size_t i = 0;
  if (u8) {
    __m256i acc[4] = {_mm256_setzero_si256(), _mm256_setzero_si256(), _mm256_setzero_si256(),
                      _mm256_setzero_si256()};
    for (; i + 128 <= bytes; i += 128)
      for (int k = 0; k < 4; ++k)
        acc[k] = _mm256_add_epi64(
            acc[k],
            _mm256_sad_epu8(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + i + 32 * k)),
                            _mm256_setzero_si256()));
    alignas(32) std::uint64_t lanes[4];
    _mm256_store_si256(
        reinterpret_cast<__m256i*>(lanes),
        _mm256_add_epi64(_mm256_add_epi64(acc[0], acc[1]), _mm256_add_epi64(acc[2], acc[3])));
    double total = double(lanes[0] + lanes[1] + lanes[2] + lanes[3]);
    for (; i < bytes; ++i) total += p[i];
    return total;
  }
  const auto* f = static_cast<const float*>(data);
  const std::size_t n = bytes / 4;
  __m256 acc[8];
  for (auto& a : acc) a = _mm256_setzero_ps();
  for (; i + 64 <= n; i += 64)
    for (int k = 0; k < 8; ++k) acc[k] = _mm256_add_ps(acc[k], _mm256_loadu_ps(f + i + 8 * k));
  for (int k = 1; k < 8; ++k) acc[0] = _mm256_add_ps(acc[0], acc[k]);
  alignas(32) float lanes[8];
  _mm256_store_ps(lanes, acc[0]);
  double total = 0;
  for (float l : lanes) total += l;
  for (; i < n; ++i) total += f[i];
  return total;
#else
  double total = 0;
  if (u8)
    for (std::size_t i = 0; i < bytes; ++i) total += static_cast<const std::uint8_t*>(data)[i];
  else
    for (std::size_t i = 0; i < bytes / 4; ++i) total += static_cast<const float*>(data)[i];
  return total;
#endif
}

// Arithmetic: `fmas` fused multiply-adds in 16 independent vector chains.
LP_FLOOR_TARGET float fmaRun(std::size_t fmas) {
#if defined(__x86_64__)
  __m256 acc[16];
  const __m256 k = _mm256_set1_ps(0.999999f), x = _mm256_set1_ps(1e-7f);
  for (auto& a : acc) a = _mm256_set1_ps(1.0f);
  for (std::size_t step = 0; step < fmas / 128; ++step)
    for (int j = 0; j < 16; ++j) acc[j] = _mm256_fmadd_ps(acc[j], k, x);
  for (int j = 1; j < 16; ++j) acc[0] = _mm256_add_ps(acc[0], acc[j]);
  alignas(32) float lanes[8];
  _mm256_store_ps(lanes, acc[0]);
  return lanes[0];
#else
  float a = 1.0f;
  for (std::size_t step = 0; step < fmas; ++step) a = a * 0.999999f + 1e-7f;
  return a;
#endif
}

// Times `task(0..tasks-1)` split across the pool (or on this thread), after one untimed run.
void timeOnThreads(benchmark::State& state, lp::ThreadPool* workers, unsigned tasks,
                   const std::function<void(unsigned)>& task) {
  auto run = [&] {
    if (workers)
      workers->run(tasks, task);
    else
      task(0);
  };
  run();
  for (auto _ : state) run();
}

void readFloor(benchmark::State& state, bool u8, Size s, int threads) {
  const void* data = u8 ? static_cast<const void*>(skyU8(s).data()) : skyF32(s).data();
  const std::size_t bytes = std::size_t(s.w) * s.h * 3 * (u8 ? 1 : 4);
  lp::ThreadPool* workers = pool(threads);
  const unsigned tasks = unsigned(threads);
  std::vector<double> partial(tasks);
  auto band = [&](unsigned t) {
    const std::size_t rows = std::size_t(s.h), a = rows * t / tasks, b = rows * (t + 1) / tasks;
    const std::size_t row = bytes / rows;
    partial[t] = readSum(static_cast<const std::uint8_t*>(data) + a * row, (b - a) * row, u8);
  };
  timeOnThreads(state, workers, tasks, band);
  benchmark::DoNotOptimize(partial);
  state.counters["GB_per_s"] =
      benchmark::Counter(double(bytes) * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}

// 15 FMAs per pixel: the separable equirect projection's arithmetic (five column-weighted sums
// per channel).
void fmaFloor(benchmark::State& state, Size s, int threads) {
  lp::ThreadPool* workers = pool(threads);
  const std::size_t fmas = std::size_t(s.w) * s.h * 15;
  const unsigned tasks = unsigned(threads);
  std::vector<float> out(tasks);
  auto work = [&](unsigned t) { out[t] = fmaRun(fmas / tasks); };
  timeOnThreads(state, workers, tasks, work);
  benchmark::DoNotOptimize(out);
  state.counters["GFMA_per_s"] =
      benchmark::Counter(double(fmas) * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}

// The replay pipeline, stage by stage, on pano.mp4 (1920x1080 H.264).
void pipelineBench(benchmark::State& state, int stage) {
  static auto source = lp::openSource(std::string(LIVEPROBE_DATA_DIR) + "/video/pano.mp4");
  static lp::Frame frame;
  if (frame.bgr8.empty()) source->next(frame);
  const lp::Linearizer lin;
  static const lp::Projector proj(lp::Layout::Equirect, 1920, 1080);
  lp::Image image;
  for (auto _ : state) {
    switch (stage) {
      case 0:  // grab: decode the next frame
        if (!source->next(frame)) {
          source->rewind();
          source->next(frame);
        }
        break;
      case 1:  // convert: linear copy for display
        benchmark::DoNotOptimize(lin.convert(frame, image));
        break;
      case 2:  // project: fused lookup table + projection, 2 threads
        benchmark::DoNotOptimize(proj.project(
            lp::PanoramaView::bgrU8(frame.bgr8.data(), 1920, 1080, lin.table().data()), pool(2)));
        break;
    }
  }
}

// One 8-bit sRGB frame of a radiance map (RGB floats) at exposure t.
lp::Frame shootSrgb(const std::vector<float>& radiance, Size s, double t) {
  lp::Frame f;
  f.format = lp::PanoramaFormat::BgrU8;
  f.width = s.w, f.height = s.h;
  f.radianceScale = 1.0 / t;
  f.bgr8.resize(radiance.size());
  for (std::size_t i = 0; i < radiance.size(); i += 3)
    for (int c = 0; c < 3; ++c)
      f.bgr8[i + 2 - std::size_t(c)] = std::uint8_t(std::lround(
          255 * lp::linearToSrgb(std::min(1.0f, float(radiance[i + std::size_t(c)] * t)))));
  return f;
}

// Two brackets of a camera turning 1 degree a frame about a tilted axis: quarry_01 (a sun over
// a quarry) at -13, -7 and 0 EV (0 EV: its median at mid-grey).
std::vector<lp::Frame> turningBrackets(Size s) {
  const lp::Image full =
      lp::loadImage(std::string(LIVEPROBE_DATA_DIR) + "/equirect/quarry_01_1k.hdr");
  const lp::Image map = lp::resampleToEquirect(full, {}, s.w, s.h);
  std::vector<float> green;
  for (std::size_t i = 1; i < map.rgb.size(); i += 3) green.push_back(map.rgb[i]);
  std::nth_element(green.begin(), green.begin() + green.size() / 2, green.end());
  const double t0 = 0.18 / green[green.size() / 2];
  const double axis[3] = {0.57735, 0.57735, 0.57735};
  std::vector<lp::Frame> frames;
  for (int n = 0; n < 6; ++n)
    frames.push_back(
        shootSrgb(lpt::turnedMap(map, axis, n).rgb, s, t0 * std::exp2((n % 3 - 2) * 6.5)));
  return frames;
}

// An exposure bracket's merge, as live --bracket does each frame. Still: the synthetic sky (its
// sun about 11 stops over the sky) at -12, -6 and 0 EV; the camera's turn is estimated and found
// to be none. Turning: turningBrackets(), the older frames turned to the newest before they
// merge. Project: the projection of the merged frame (float RGB, the same threads), the second
// pass a merge for a light search is followed by. Projecting: the still merge projecting as it
// merges and writing no frame, as a pipeline asked for the coefficients alone does
// (PipelineOptions::keepImages off). docs/speed.md gives the ratios to Project.
enum class MergeCase { Still, Turning, Project, Projecting };
void mergeBench(benchmark::State& state, Size s, int threads, MergeCase what) {
  std::vector<lp::Frame> frames;
  if (what == MergeCase::Turning) {
    frames = turningBrackets(s);
  } else {
    for (const double stops : {-12.0, -6.0, 0.0})  // 0 EV: the sky's median near mid-grey
      frames.push_back(shootSrgb(skyF32(s), s, 0.1 * std::exp2(stops)));
  }
  lp::BracketMerger merger({.frames = 3});
  lp::Frame out;
  lp::ThreadPool* workers = pool(threads);
  const lp::Projector projector(lp::Layout::Equirect, s.w, s.h);
  lp::MergeProjection projecting{.integrals = projector.equirectIntegrals(), .keepFrame = false};
  std::uint64_t sequence = 0;
  const auto add = [&] {
    lp::Frame& f = frames[sequence % frames.size()];
    f.sequence = sequence++;  // a camera's stream: one frame after another
    return what == MergeCase::Projecting ? merger.add(f, out, workers, projecting)
                                         : merger.add(f, out, workers);
  };
  for (int i = 0; i < 3; ++i) add();  // untimed: full
  if (what == MergeCase::Project) {
    const auto view = lp::PanoramaView::rgbF32(out.rgb.data(), s.w, s.h);
    benchmark::DoNotOptimize(projector.project(view, workers));
    for (auto _ : state) benchmark::DoNotOptimize(projector.project(view, workers));
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(add());
}

void registerAll() {
  // Angular maps are square: their sizes keep the equirect's pixel counts roughly.
  // A lens's frames are a camera's: 4:3 from 1280x960 up.
  const std::vector<std::pair<lp::LayoutSpec, std::vector<Size>>> layouts = {
      {lp::Layout::Equirect, {{300, 300}, {1024, 512}, {2048, 1024}, {3840, 1920}}},
      {lp::Layout::Angular, {{300, 300}, {1024, 1024}, {2048, 2048}}},
      {benchLens(), {{1280, 960}, {2560, 1920}}}};
  for (const auto& [layout, sizes] : layouts)
    for (const char* type : {"f32", "u8"})
      for (Size s : sizes)
        for (int threads : {1, 2})
          for (const std::string& simd : lp::simd::available()) {  // every path this CPU runs
            const bool u8 = std::string(type) == "u8";
            const std::string name = "Project/" + std::string(lp::layoutName(layout.layout)) + "/" +
                                     type + "/" + sizeName(s) +
                                     "/threads:" + std::to_string(threads) + "/simd:" + simd;
            benchmark::RegisterBenchmark(
                name.c_str(),
                [=](benchmark::State& st) { projectBench(st, layout, u8, s, threads, simd); })
                ->UseRealTime()
                ->Unit(benchmark::kMicrosecond);
          }
  // The floors, for the equirect sizes: reading the frame, and 15 FMAs per pixel.
  for (Size s : layouts[0].second)
    for (int threads : {1, 2}) {
      const std::string tail = sizeName(s) + "/threads:" + std::to_string(threads);
      for (const char* type : {"f32", "u8"})
        benchmark::RegisterBenchmark(
            ("Floor/read/" + std::string(type) + "/" + tail).c_str(),
            [=](benchmark::State& st) { readFloor(st, std::string(type) == "u8", s, threads); })
            ->UseRealTime()
            ->Unit(benchmark::kMicrosecond);
      benchmark::RegisterBenchmark(("Floor/fma/" + tail).c_str(),
                                   [=](benchmark::State& st) { fmaFloor(st, s, threads); })
          ->UseRealTime()
          ->Unit(benchmark::kMicrosecond);
    }
  for (const char* type : {"u8", "f32"})
    for (Size s : {Size{1920, 1080}, Size{3840, 1920}})
      for (const int mode : {0, 1, 2})
        benchmark::RegisterBenchmark(
            ("Lights/equirect/" + std::string(type) + "/" + sizeName(s) + "/threads:2/" +
             (mode == 0   ? "project"
              : mode == 1 ? "project+lights"
                          : "lights"))
                .c_str(),
            [=](benchmark::State& st) { lightsBench(st, std::string(type) == "u8", s, mode); })
            ->UseRealTime()
            ->Unit(benchmark::kMicrosecond);
  for (Size s : {Size{1024, 1024}, Size{1280, 960}, Size{2560, 1920}})
    benchmark::RegisterBenchmark(("Reference/plain/f32/" + sizeName(s) + "/threads:1").c_str(),
                                 [=](benchmark::State& st) { plainLoop(st, s); })
        ->UseRealTime()
        ->Unit(benchmark::kMicrosecond);
  for (Size s : {Size{300, 300}, Size{3840, 1920}})
    benchmark::RegisterBenchmark(("Reference/equirect/f32/" + sizeName(s) + "/threads:1").c_str(),
                                 [=](benchmark::State& st) { referenceLoop(st, s); })
        ->UseRealTime()
        ->Unit(benchmark::kMicrosecond);
  for (int threads : {1, 2})
    benchmark::RegisterBenchmark(
        ("Brute/equirect/f32/300x300/T:64x64/threads:" + std::to_string(threads)).c_str(),
        [=](benchmark::State& st) { bruteBench(st, threads); })
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond)
        ->Iterations(3);
  benchmark::RegisterBenchmark("Render/bunny/1280x720/osmesa", renderBench)
      ->UseRealTime()
      ->Unit(benchmark::kMillisecond);
  for (Size s : {Size{1920, 960}, Size{3840, 1920}})
    for (int threads : {1, 2})
      for (const auto& [what, name] :
           {std::pair{MergeCase::Still, "merge"}, std::pair{MergeCase::Turning, "turning"},
            std::pair{MergeCase::Project, "project"},
            std::pair{MergeCase::Projecting, "merge+project"}})
        benchmark::RegisterBenchmark(
            ("Merge/bracket:3/u8/" + sizeName(s) + "/threads:" + std::to_string(threads) + "/" +
             name)
                .c_str(),
            [=](benchmark::State& st) { mergeBench(st, s, threads, what); })
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
  const char* stages[] = {"grab", "convert", "project"};
  for (int i = 0; i < 3; ++i)
    benchmark::RegisterBenchmark(
        ("Pipeline/pano.mp4/u8/1920x1080/" + std::string(stages[i])).c_str(),
        [=](benchmark::State& st) { pipelineBench(st, i); })
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond);
}

}  // namespace

int main(int argc, char** argv) {
  registerAll();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
