// liveprobe-gpu-bench: what the GPU costs, per frame size and pixel type, beside the CPU.
//   Upload/.../direct  glTexSubImage2D from ordinary memory, waited for (glFinish)
//   Upload/.../pbo     the frame copied into a mapped pixel-buffer object, then the transfer
//   ReadFloor/...      a compute pass that only reads every texel: the memory floor
//   Project/.../gpu    the projection's two compute passes on the uploaded frame, waited for
//   Project/.../cpu    lp::Projector on every hardware thread
//   Render/bunny/...   the baked Stanford bunny, 4x MSAA, with the background, waited for
//   Frame/u8/.../serial      write, transfer, project and render one after another
//   Frame/u8/.../overlapped  the same with nothing waited for: the CPU writes frame n + 1 while
//                            the GPU works on frame n; coefficients read one frame late
//   Merge/u8x3/.../gpu       a bracket of three 8-bit frames merged and projected in one pass,
//                            the newest frame uploaded each merge, as a camera's stream runs it
//   Merge/u8x3/.../gpu/resident  the same pass with the three frames on the GPU already
//   Merge/u8x3/.../gpu/resident/parts:N  with each row merged in N workgroups
//   Merge/u8x3/.../gpu/resident/group:N  in workgroups of N invocations (128 otherwise; 512
//                            takes more shared memory than GL promises, 32 kB)
//   Merge/u8x3/.../gpu/resident/unprojected  without the projection (a light search's merge)
//   Merge/u8x3/.../gpu/resident/bound:no-judgement  a bound, not the CPU's merge (not checked):
//                            every reading at its hat weight, no contradiction judged
//   Merge/u8x3/.../cpu       the CPU's merge row kernel on every hardware thread
//   Frame/u8x3/.../merge/... a bracketed frame: the newest frame's upload, the merge and its
//                            projection, and the bunny rendered at 1080p before a still sky;
//                            .../merge/background/... before the merged frame, kept on the GPU
//                            and copied into the background there; .../background:readback/...
//                            the merged frame read back and uploaded
// gpu_us counters are GL timer queries (absent where the GL has no timer, as llvmpipe).
// Every Project/gpu and Merge/gpu run (bar the bound) first checks the GPU's sums against the CPU's
// (1e-5) and stops the benchmark with an error where they differ.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "liveprobe/gl/context.h"
#include "liveprobe/gl/gpu_merge.h"
#include "liveprobe/gl/gpu_projector.h"
#include "liveprobe/gl/gpu_timer.h"
#include "liveprobe/gl/mesh.h"
#include "liveprobe/gl/renderer.h"
#include "liveprobe/hdr/merge_frame.h"
#include "liveprobe/sh/executor.h"
#include "liveprobe/sh/projector.h"
#include "merge_kernel.h"

extern "C" const char lp_baked_model[];
extern "C" const char lp_baked_model_end[];

namespace {

using lp::gl::GpuTimer;

/// Set where a GPU projection disagrees with the CPU's: the run then exits 1.
bool gMismatch = false;

struct Size {
  int w, h;
};
std::string sizeName(Size s) { return std::to_string(s.w) + "x" + std::to_string(s.h); }

/// One context for the whole run, as large as the largest render.
lp::gl::GlContext& context() {
  static auto ctx = [] {
    lp::gl::ContextSpec spec;
    spec.backend = lp::gl::Backend::Headless;
    spec.width = 3840, spec.height = 2160;
    spec.title = "liveprobe-gpu-bench";
    return lp::gl::createGlContext(spec);
  }();
  return *ctx;
}

/// A sky: a blue gradient, a bright ground band and a sun of 2e4 (a real one's ratio).
std::vector<float> skyF32(Size s) {
  std::vector<float> px(std::size_t(s.w) * std::size_t(s.h) * 3);
  for (int i = 0; i < s.h; ++i)
    for (int j = 0; j < s.w; ++j) {
      const float v = (i + 0.5f) / float(s.h), u = (j + 0.5f) / float(s.w);
      float* p = &px[(std::size_t(i) * std::size_t(s.w) + std::size_t(j)) * 3];
      const float du = u - 0.3f, dv = v - 0.25f;
      const bool sun = du * du * 4.0f + dv * dv < 0.0004f;
      p[0] = sun ? 2e4f : (v < 0.5f ? 0.3f + 0.4f * v : 0.2f);
      p[1] = sun ? 1.8e4f : (v < 0.5f ? 0.5f + 0.3f * v : 0.18f);
      p[2] = sun ? 1.5e4f : (v < 0.5f ? 0.9f - 0.2f * v : 0.12f);
    }
  return px;
}

/// The same sky as 8-bit codes (clipped, gamma 2.2) and the table that decodes them.
struct FrameU8 {
  std::vector<std::uint8_t> codes;
  std::array<float, 256> decode;
};
FrameU8 skyU8(Size s) {
  const auto f = skyF32(s);
  FrameU8 out;
  out.codes.resize(f.size());
  for (std::size_t i = 0; i < f.size(); ++i)
    out.codes[i] = std::uint8_t(std::lround(255.0f * std::pow(std::min(f[i], 1.0f), 1 / 2.2f)));
  for (int c = 0; c < 256; ++c) out.decode[std::size_t(c)] = std::pow(c / 255.0f, 2.2f);
  return out;
}

/// A frame of either type, in memory, with its view.
struct TestFrame {
  std::vector<float> f32;
  FrameU8 u8;
  lp::PanoramaView view;
};
void fillFrame(TestFrame& t, Size s, bool u8) {
  if (u8) {
    t.u8 = skyU8(s);
    t.view = lp::PanoramaView{t.u8.codes.data(), lp::PanoramaFormat::RgbU8, s.w, s.h, 0, {},
                              t.u8.decode.data()};
  } else {
    t.f32 = skyF32(s);
    t.view = lp::PanoramaView::rgbF32(t.f32.data(), s.w, s.h);
  }
}

/// Frames are made once per size and type (an 8K one takes seconds), kept for the run.
const TestFrame& makeFrame(Size s, bool u8) {
  static std::map<std::tuple<int, int, bool>, std::unique_ptr<TestFrame>> frames;
  auto& f = frames[{s.w, s.h, u8}];
  if (!f) {
    f = std::make_unique<TestFrame>();  // the view points into it: made in place
    fillFrame(*f, s, u8);
  }
  return *f;
}

/// Timer-query milliseconds of one stage, averaged over the frames that answered (each frame
/// once: what the timer's last beginFrame() read).
struct GpuMs {
  double sum = 0;
  int n = 0;
  void add(const GpuTimer& t, GpuTimer::Stage s) {
    if (auto ms = t.justRead(s)) sum += *ms, ++n;
  }
  void report(benchmark::State& state, const char* name) const {
    if (n > 0) state.counters[name] = sum / n * 1e3;
  }
};

/// After a loop: waits for the GPU, then reads every frame still in flight (`add` after each
/// beginFrame()), so that a run of fewer frames than the timer's latency reports too.
template <class Add>
void drain(GpuTimer& timer, Add add) {
  glFinish();
  for (int k = 0; k <= GpuTimer::kLatency; ++k) {
    timer.beginFrame();
    add();
  }
}

/// Runs `work` once an iteration under the stage's timer query, then `after` (glFinish, or the
/// wait for a result), and reports the stage's GPU time as gpu_us.
template <class Work, class After>
void timedLoop(benchmark::State& state, GpuTimer::Stage stage, Work work, After after) {
  GpuTimer timer;
  GpuMs gpu;
  glFinish();
  for (auto _ : state) {
    timer.beginFrame();
    gpu.add(timer, stage);
    timer.begin(stage);
    work();
    timer.end();
    after();
  }
  drain(timer, [&] { gpu.add(timer, stage); });
  gpu.report(state, "gpu_us");
}

/// The CPU's write of a frame into the mapped buffer (its seconds returned), then the transfer
/// queued under the upload timer.
double writeAndCommit(lp::gl::FrameTexture& tex, const lp::PanoramaView& frame, GpuTimer& timer) {
  const auto t0 = std::chrono::steady_clock::now();
  void* dst = tex.map(frame.format, frame.width, frame.height);
  std::memcpy(dst, frame.data, tex.frameBytes());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  timer.begin(GpuTimer::Upload);
  tex.commit();
  timer.end();
  return seconds;
}

void uploadDirect(benchmark::State& state, Size s, bool u8) {
  context();
  const TestFrame& frame = makeFrame(s, u8);
  lp::gl::FrameTexture tex;
  tex.upload(frame.view);  // the texture, allocated once
  const GLenum type = u8 ? GL_UNSIGNED_BYTE : GL_FLOAT;
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  timedLoop(
      state, GpuTimer::Upload,
      [&] {
        glBindTexture(GL_TEXTURE_2D, tex.texture());
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, s.w, s.h, GL_RGB, type, frame.view.data);
      },
      glFinish);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(tex.frameBytes()));
}

void uploadPbo(benchmark::State& state, Size s, bool u8) {
  context();
  const TestFrame& frame = makeFrame(s, u8);
  lp::gl::FrameTexture tex;
  tex.upload(frame.view);
  GpuTimer timer;
  GpuMs gpu;
  double writeSeconds = 0;
  for (auto _ : state) {
    timer.beginFrame();
    gpu.add(timer, GpuTimer::Upload);
    writeSeconds += writeAndCommit(tex, frame.view, timer);
    glFinish();
  }
  drain(timer, [&] { gpu.add(timer, GpuTimer::Upload); });
  gpu.report(state, "gpu_us");
  state.counters["cpu_write_us"] = writeSeconds / double(state.iterations()) * 1e6;
  state.counters["persistent"] = tex.persistent() ? 1 : 0;
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(tex.frameBytes()));
}

// Reads every texel once and writes one sum per workgroup: the least a pass over the frame costs.
const char* const kFloorCs = R"(#version 430
layout(local_size_x = 256) in;
layout(binding = 0) uniform sampler2D frame;
layout(std430, binding = 0) writeonly buffer Out { float outv[]; };
uniform int width, height, rowsPerGroup;
shared float red[256];
void main() {
  const uint lid = gl_LocalInvocationID.x;
  const int j = int(gl_WorkGroupID.x) * 256 + int(lid);
  const int i0 = int(gl_WorkGroupID.y) * rowsPerGroup, i1 = min(i0 + rowsPerGroup, height);
  vec3 acc = vec3(0.0);
  if (j < width)
    for (int i = i0; i < i1; ++i) acc += texelFetch(frame, ivec2(j, i), 0).rgb;
  red[lid] = acc.r + acc.g + acc.b;
  barrier();
  for (uint s = 128u; s > 0u; s >>= 1) {
    if (lid < s) red[lid] += red[lid + s];
    barrier();
  }
  if (lid == 0u) outv[gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x] = red[0];
}
)";

GLuint floorProgram() {
  static GLuint program = [] {
    const GLuint sh = glCreateShader(GL_COMPUTE_SHADER);
    glShaderSource(sh, 1, &kFloorCs, nullptr);
    glCompileShader(sh);
    const GLuint p = glCreateProgram();
    glAttachShader(p, sh);
    glLinkProgram(p);
    glDeleteShader(sh);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) throw std::runtime_error("the floor's compute shader does not link");
    return p;
  }();
  return program;
}

/// The context, the frame and its texture, for a run that needs compute shaders: nullptr (and
/// the run marked) where the context has none. Made once per size and type and kept for the run:
/// Google Benchmark calls a benchmark's function several times (to size the run, then once a
/// repetition), and at 8K the buffers' allocation and the upload take longer than the timing.
struct Uploaded {
  const TestFrame& frame;
  lp::gl::FrameTexture tex;
};
Uploaded* uploaded(benchmark::State& state, Size s, bool u8) {
  context();
  if (!lp::gl::hasCompute()) {
    state.SkipWithError("no compute shaders (GL 4.3)");
    return nullptr;
  }
  static std::map<std::tuple<int, int, bool>, std::unique_ptr<Uploaded>> kept;
  auto& u = kept[{s.w, s.h, u8}];
  if (!u) {
    u = std::unique_ptr<Uploaded>(new Uploaded{makeFrame(s, u8), {}});
    u->tex.upload(u->frame.view);
  }
  return u.get();
}

void readFloor(benchmark::State& state, Size s, bool u8) {
  auto up = uploaded(state, s, u8);
  if (!up) return;
  lp::gl::FrameTexture& tex = up->tex;
  const int rows = std::clamp(s.h * ((s.w + 255) / 256) / 512, 4, 64);
  const int gx = (s.w + 255) / 256, gy = (s.h + rows - 1) / rows;
  GLuint out = 0;
  glGenBuffers(1, &out);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, out);
  glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(gx) * gy * 4, nullptr, GL_DYNAMIC_COPY);
  const GLuint p = floorProgram();
  glUseProgram(p);
  glUniform1i(glGetUniformLocation(p, "width"), s.w);
  glUniform1i(glGetUniformLocation(p, "height"), s.h);
  glUniform1i(glGetUniformLocation(p, "rowsPerGroup"), rows);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, out);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, tex.texture());
  timedLoop(
      state, GpuTimer::Project, [&] { glDispatchCompute(GLuint(gx), GLuint(gy), 1); }, glFinish);
  glUseProgram(0);
  glDeleteBuffers(1, &out);
}

/// Largest |a - b| over the 27 values, over |L00| of b (its largest channel).
double relativeError(const lp::Sh9& a, const lp::Sh9& b) {
  double worst = 0;
  for (int k = 0; k < lp::kShCount; ++k)
    for (int c = 0; c < 3; ++c) worst = std::max(worst, double(std::abs(a.c[k][c] - b.c[k][c])));
  const float l00 = std::max({std::abs(b.c[0].x), std::abs(b.c[0].y), std::abs(b.c[0].z)});
  return worst / double(l00);
}

/// A projector for the size and rows per group, and its coefficients' distance from the CPU's
/// for the frame of that type: made and checked once, kept for the run.
struct CheckedProjector {
  std::unique_ptr<lp::gl::GpuProjector> gpu;
  double error = 0;
};
CheckedProjector& checkedProjector(const Uploaded& up, Size s, bool u8, int rows) {
  static std::map<std::tuple<int, int, bool, int>, CheckedProjector> kept;
  CheckedProjector& c = kept[{s.w, s.h, u8, rows}];
  if (!c.gpu) {
    c.gpu = std::make_unique<lp::gl::GpuProjector>(lp::Layout::Equirect, s.w, s.h, rows);
    lp::ThreadPool pool(0);
    const lp::Sh9 cpu = lp::Projector(lp::Layout::Equirect, s.w, s.h).project(up.frame.view, &pool);
    c.error = relativeError(c.gpu->project(up.tex, up.frame.view.decode), cpu);
  }
  return c;
}

void projectGpu(benchmark::State& state, Size s, bool u8, int rows = 0) {
  auto up = uploaded(state, s, u8);
  if (!up) return;
  const TestFrame& frame = up->frame;
  lp::gl::FrameTexture& tex = up->tex;
  CheckedProjector& checked = checkedProjector(*up, s, u8, rows);
  lp::gl::GpuProjector& gpu = *checked.gpu;
  if (!(checked.error <= 1e-5)) {
    char why[128];
    std::snprintf(why, sizeof why, "the GPU's coefficients are %.3g of L00 from the CPU's",
                  checked.error);
    gMismatch = true;
    return state.SkipWithError(why);
  }
  timedLoop(
      state, GpuTimer::Project, [&] { gpu.dispatch(tex, frame.view.decode); },
      [&] { benchmark::DoNotOptimize(gpu.read(true)); });
  state.counters["error_of_L00"] = checked.error;
  state.counters["groups"] = gpu.groups();
  state.counters["rows"] = gpu.rowsPerGroup();
}

void projectCpu(benchmark::State& state, Size s, bool u8) {
  const TestFrame& frame = makeFrame(s, u8);
  lp::ThreadPool pool(0);
  const lp::Projector projector(lp::Layout::Equirect, s.w, s.h);
  for (auto _ : state) benchmark::DoNotOptimize(projector.project(frame.view, &pool));
  state.counters["threads"] = pool.concurrency();
}

/// The bunny, lit by the sky, over the sky's background, at `size` with 4x MSAA.
struct BunnyScene {
  lp::gl::Renderer renderer;
  explicit BunnyScene(Size background) {
    lp::Mesh mesh = lp::meshFromObjText(
        std::string_view(lp_baked_model, std::size_t(lp_baked_model_end - lp_baked_model)));
    lp::fitToUnitSphere(mesh);
    renderer.setMesh(mesh);
    const auto sky = skyF32(background);
    renderer.setLighting(
        lp::project(lp::PanoramaView::rgbF32(sky.data(), background.w, background.h)));
    renderer.setBackground(sky.data(), background.w, background.h,
                           lp::gl::BackgroundMapping::Equirect);
  }
  void draw(Size s) {
    lp::gl::ShadingSettings settings;
    settings.samples = 4;
    renderer.draw({s.w, s.h}, lp::gl::Camera{}, settings);
  }
};

void renderBunny(benchmark::State& state, Size s) {
  context();
  BunnyScene scene({1920, 960});
  timedLoop(
      state, GpuTimer::Render, [&] { scene.draw(s); }, glFinish);
}

/// A camera's 8-bit frame: the CPU writes it into the mapped buffer, the GPU transfers it,
/// projects it and renders the bunny at 1080p lit by the coefficients of the frame before.
void frameLoop(benchmark::State& state, Size s, bool overlapped) {
  auto up = uploaded(state, s, true);
  if (!up) return;
  const TestFrame& frame = up->frame;
  lp::gl::FrameTexture& tex = up->tex;
  lp::gl::GpuProjector gpu(lp::Layout::Equirect, s.w, s.h);
  BunnyScene scene({1920, 960});
  GpuTimer timer;
  GpuMs upload, project, render;
  double writeSeconds = 0;
  int late = 0;
  glFinish();
  for (auto _ : state) {
    timer.beginFrame();
    upload.add(timer, GpuTimer::Upload);
    project.add(timer, GpuTimer::Project);
    render.add(timer, GpuTimer::Render);
    writeSeconds += writeAndCommit(tex, frame.view, timer);
    if (!overlapped) glFinish();
    // The coefficients of the frame before, if the GPU has them (never waited for here).
    if (auto sh = gpu.read(false))
      scene.renderer.setLighting(*sh);
    else if (gpu.pending() > 0)
      ++late;
    timer.begin(GpuTimer::Project);
    gpu.dispatch(tex, frame.view.decode);
    timer.end();
    if (!overlapped) glFinish();
    timer.begin(GpuTimer::Render);
    scene.draw({1920, 1080});
    timer.end();
    if (!overlapped) glFinish();
  }
  drain(timer, [&] {
    upload.add(timer, GpuTimer::Upload);
    project.add(timer, GpuTimer::Project);
    render.add(timer, GpuTimer::Render);
  });
  while (gpu.pending() > 0) gpu.read(true);
  upload.report(state, "gpu_upload_us");
  project.report(state, "gpu_project_us");
  render.report(state, "gpu_render_us");
  state.counters["cpu_write_us"] = writeSeconds / double(state.iterations()) * 1e6;
  state.counters["coeffs_late"] = late;
}

/// The GPU's multiprocessors and the warps each holds, where the GL says
/// (NV_shader_thread_group): what the rows-per-group sweep's group counts are measured against.
std::string multiprocessors() {
  GLint n = 0;
  glGetIntegerv(GL_NUM_EXTENSIONS, &n);
  for (GLint i = 0; i < n; ++i)
    if (std::strcmp(reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, GLuint(i))),
                    "GL_NV_shader_thread_group") == 0) {
      GLint sms = 0, warps = 0;
      glGetIntegerv(0x933B, &sms);    // GL_SM_COUNT_NV
      glGetIntegerv(0x933A, &warps);  // GL_WARPS_PER_SM_NV
      return std::to_string(sms) + " SMs, " + std::to_string(warps) + " warps each";
    }
  return "not reported";
}

/// A bracket of three 8-bit frames of the sky at 1/65536, 1/256 and 1 s (the sun measured by the
/// first, the sky by the others), decoded through the gamma table, as a still camera's stream
/// hands it to a merge: the merge's input, and the buffers it points into.
struct MergeBracket {
  std::array<std::vector<std::uint8_t>, 3> codes;
  FrameU8 table = skyU8({1, 1});
  std::vector<float> previous, reference, luminance;
  lp::Projector projector;
  lp::merge::FrameInput in;
  explicit MergeBracket(Size s) : projector(lp::Layout::Equirect, s.w, s.h) {
    const std::vector<float> sky = skyF32(s);
    const double times[3] = {1.0 / 65536, 1.0 / 256, 1.0};
    in.frames = 3, in.longest = 2, in.width = s.w, in.height = s.h;
    for (int k = 0; k < 3; ++k) {
      auto& c = codes[std::size_t(k)];
      c.resize(sky.size());
      for (std::size_t i = 0; i < sky.size(); ++i)  // B, G, R
        c[i / 3 * 3 + 2 - i % 3] = std::uint8_t(
            std::lround(255.0f * std::pow(std::min(float(sky[i] * times[k]), 1.0f), 1 / 2.2f)));
      in.bgr[k] = c.data();
      in.scale[k] = float(1.0 / times[k]);
    }
    for (const float*& lut : in.lut) lut = table.decode.data();
    in.floor = 6, in.clip = 250, in.wellExposed = 16;
    in.wellLinear = table.decode[16], in.belowClipLinear = table.decode[200];
    in.inv2s2 = float(1.0 / (2 * 0.3 * 0.3));
    const std::size_t pixels = std::size_t(s.w) * std::size_t(s.h);
    previous.assign(pixels, 0.0f), reference.assign(pixels, 0.0f), luminance.assign(pixels, 0.0f);
    in.previous = previous.data(), in.reference = reference.data();
    in.luminance = luminance.data();
    in.fresh = true;
    in.luminanceBack = false;  // kept on the GPU, as a live run keeps it
    for (int k = 0; k < 5; ++k)
      in.col[k] = projector.equirectIntegrals()->col[std::size_t(k)].data();
  }
};

/// The CPU's row kernel (the merge's SIMD path) over every row on `pool`.
std::vector<lp::merge::RowSums> mergeOnCpu(const lp::merge::FrameInput& in, lp::Executor* pool) {
  std::vector<lp::merge::RowSums> rows(std::size_t(in.height));
  const lp::merge::RowKernel kernel = lp::merge::active();
  lp::parallelFor(pool, rows.size(), lp::Split{}, [&](std::size_t y0, std::size_t y1) {
    for (std::size_t y = y0; y < y1; ++y) rows[y] = kernel(lp::merge::RowInput::of(in, y));
  });
  return rows;
}

/// The GPU's row sums against the CPU's: every row's dark count and peak (within 1e-5), and the
/// whole frame's power and column-weighted sums (what the coefficients are made of) within 1e-5
/// of the largest.
std::string mergeDisagreement(const std::vector<lp::merge::RowSums>& gpu,
                              const std::vector<lp::merge::RowSums>& cpu) {
  double g[16] = {}, c[16] = {};
  for (std::size_t y = 0; y < cpu.size(); ++y) {
    if (gpu[y].dark != cpu[y].dark)
      return "row " + std::to_string(y) + ": " + std::to_string(gpu[y].dark) + " dark pixels, " +
             "the CPU's " + std::to_string(cpu[y].dark);
    if (std::abs(gpu[y].peak - cpu[y].peak) > 1e-5f * cpu[y].peak)
      return "row " + std::to_string(y) + ": peak " + std::to_string(gpu[y].peak) + ", the CPU's " +
             std::to_string(cpu[y].peak);
    g[15] += gpu[y].power, c[15] += cpu[y].power;
    for (int k = 0; k < 5; ++k)
      for (int ch = 0; ch < 3; ++ch)
        g[k * 3 + ch] += gpu[y].col[k][ch], c[k * 3 + ch] += cpu[y].col[k][ch];
  }
  double largest = 0;
  for (double v : c) largest = std::max(largest, std::abs(v));
  for (int i = 0; i < 16; ++i)
    if (std::abs(g[i] - c[i]) > 1e-5 * largest)
      return (i == 15 ? std::string("power") : "column sum " + std::to_string(i)) + ": " +
             std::to_string(g[i]) + ", the CPU's " + std::to_string(c[i]);
  return {};
}

/// The bracket merge on the GPU (gl::GpuMerge, what a live --bracket run with --projection gpu
/// runs): judged per pixel and projected in the same pass, the merged frame and its luminance not
/// read back (a live run without a light search), and the row sums' readback. `streaming`: as a
/// camera's stream runs it, the newest frame uploaded each merge (the older two kept from the
/// merges before); else all three resident, the pass and its readback alone. First the GPU's sums
/// are checked against the CPU's row kernel, as the projections are.
void mergeGpu(benchmark::State& state, Size s, bool streaming, lp::gl::GpuMergeShape shape = {},
              bool projected = true) {
  context();
  if (!lp::gl::hasCompute()) return state.SkipWithError("no compute shaders (GL 4.3)");
  MergeBracket b(s);
  lp::merge::FrameInput& in = b.in;
  if (!projected) std::fill(std::begin(in.col), std::end(in.col), nullptr);
  std::unique_ptr<lp::gl::GpuMerge> made;
  try {
    made = std::make_unique<lp::gl::GpuMerge>(shape);
  } catch (const lp::gl::ContextError& e) {  // (a shape this GL cannot link)
    return state.SkipWithError(e.what());
  }
  lp::gl::GpuMerge& gpu = *made;
  std::vector<lp::merge::RowSums> rows;
  std::uint64_t next = 1;
  const auto keys = [&] {
    for (int k = 0; k < 3; ++k) in.key[k] = (streaming ? next : 1) + std::uint64_t(k);
    // The last merge's luminance kept on the GPU.
    in.previousKey = in.referenceKey = 1000000 + next - 1;
    in.luminanceKey = 1000000 + next++;
  };
  {
    keys();
    gpu(in, rows);
    lp::ThreadPool pool(0);
    lp::merge::FrameInput cpuIn = in;
    std::vector<float> luminance(b.luminance.size());
    cpuIn.luminance = luminance.data();
    // (The bound without the judgement is not the CPU's merge: not checked.)
    const std::string wrong =
        shape.judge ? mergeDisagreement(rows, mergeOnCpu(cpuIn, &pool)) : std::string();
    if (!wrong.empty()) {
      std::fprintf(stderr,
                   "liveprobe-gpu-bench: the GPU merge disagrees with the CPU's at %s: %s\n",
                   sizeName(s).c_str(), wrong.c_str());
      gMismatch = true;
      return state.SkipWithError("the GPU merge disagrees with the CPU's");
    }
  }
  timedLoop(
      state, GpuTimer::Merge,
      [&] {
        keys();
        gpu(in, rows);
      },
      [] {});
  state.counters["frames"] = in.frames;
}

/// Where a bracketed frame's background comes from: the bunny's own still sky (none), the merged
/// frame kept on the GPU and copied into the background's texture there, or the merged frame
/// read back and uploaded (a display that shares nothing with the merge's context).
enum class MergedBackground { None, Kept, ReadBack };

/// A live bracketed run's frame on the GPU: the newest 8-bit frame uploaded, the bracket merged
/// and projected (its sums read back, as the merge's confidence needs them before the frame is
/// done), then the bunny rendered at 1080p over the background.

void frameLoopMerge(benchmark::State& state, Size s, MergedBackground bg) {
  context();
  if (!lp::gl::hasCompute()) return state.SkipWithError("no compute shaders (GL 4.3)");
  MergeBracket b(s);
  lp::gl::GpuMerge gpu;
  BunnyScene scene({1920, 960});
  std::vector<lp::merge::RowSums> rows;
  std::vector<float> rgb(bg == MergedBackground::ReadBack ? std::size_t(s.w) * s.h * 3 : 0);
  b.in.rgbKept = bg == MergedBackground::Kept;
  b.in.rgb = rgb.empty() ? nullptr : rgb.data();
  GpuTimer timer;
  GpuMs merge, upload, render;
  std::uint64_t next = 1;
  glFinish();
  for (auto _ : state) {
    timer.beginFrame();
    merge.add(timer, GpuTimer::Merge);
    upload.add(timer, GpuTimer::Upload);
    render.add(timer, GpuTimer::Render);
    for (int k = 0; k < 3; ++k) b.in.key[k] = next + std::uint64_t(k);
    b.in.previousKey = b.in.referenceKey = 1000000 + next - 1;
    b.in.luminanceKey = 1000000 + next++;
    timer.begin(GpuTimer::Merge);
    gpu(b.in, rows);
    timer.end();
    timer.begin(GpuTimer::Upload);
    if (bg == MergedBackground::Kept)
      scene.renderer.setBackground(*gpu.takeKeptImage(), lp::gl::BackgroundMapping::Equirect, 1.0f);
    else if (bg == MergedBackground::ReadBack)
      scene.renderer.setBackground(rgb.data(), s.w, s.h, lp::gl::BackgroundMapping::Equirect);
    timer.end();
    timer.begin(GpuTimer::Render);
    scene.draw({1920, 1080});
    timer.end();
  }
  drain(timer, [&] {
    merge.add(timer, GpuTimer::Merge);
    upload.add(timer, GpuTimer::Upload);
    render.add(timer, GpuTimer::Render);
  });
  merge.report(state, "gpu_merge_us");
  if (bg != MergedBackground::None) upload.report(state, "gpu_background_us");
  render.report(state, "gpu_render_us");
}

/// The CPU's merge of the same bracket: the row kernel on every hardware thread.
void mergeCpu(benchmark::State& state, Size s) {
  MergeBracket b(s);
  lp::ThreadPool pool(0);
  for (auto _ : state) benchmark::DoNotOptimize(mergeOnCpu(b.in, &pool));
  state.counters["threads"] = pool.concurrency();
}

void registerAll() {
  for (Size s : {Size{300, 300}, Size{1920, 960}, Size{3840, 1920}, Size{7680, 3840}})
    for (bool u8 : {false, true}) {
      const std::string tail = (u8 ? "u8/" : "f32/") + sizeName(s);
      auto reg = [&](const std::string& name, auto fn) {
        benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& st) { fn(st, s, u8); })
            ->UseRealTime()
            ->Unit(benchmark::kMicrosecond);
      };
      reg("Upload/" + tail + "/direct", uploadDirect);
      reg("Upload/" + tail + "/pbo", uploadPbo);
      reg("ReadFloor/" + tail + "/gpu", readFloor);
      reg("Project/" + tail + "/gpu",
          [](benchmark::State& st, Size sz, bool b) { projectGpu(st, sz, b); });
      reg("Project/" + tail + "/cpu", projectCpu);
    }
  // The first pass's rows per invocation, at 4K and 8K (the default aims at about 768 groups).
  for (Size s : {Size{3840, 1920}, Size{7680, 3840}})
    for (bool u8 : {false, true})
      for (int rows : {16, 32, 64, 128, 256})
        benchmark::RegisterBenchmark(((u8 ? "Project/u8/" : "Project/f32/") + sizeName(s) +
                                      "/gpu/rows:" + std::to_string(rows))
                                         .c_str(),
                                     [=](benchmark::State& st) { projectGpu(st, s, u8, rows); })
            ->UseRealTime()
            ->Unit(benchmark::kMicrosecond);
  for (Size s : {Size{300, 300}, Size{1920, 960}, Size{3840, 1920}}) {
    const std::string name = "Merge/u8x3/" + sizeName(s);
    benchmark::RegisterBenchmark((name + "/gpu").c_str(),
                                 [=](benchmark::State& st) { mergeGpu(st, s, true); })
        ->UseRealTime()
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark((name + "/gpu/resident").c_str(),
                                 [=](benchmark::State& st) { mergeGpu(st, s, false); })
        ->UseRealTime()
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark((name + "/cpu").c_str(),
                                 [=](benchmark::State& st) { mergeCpu(st, s); })
        ->UseRealTime()
        ->Unit(benchmark::kMicrosecond);
  }
  // The workgroups a row is merged in (the default: one); the invocations of a workgroup (the
  // default: 128); the pass without its projection (a light search's merge); and a bound: the
  // pass without the per-pixel judgement.
  for (Size s : {Size{1920, 960}, Size{3840, 1920}}) {
    const std::string name = "Merge/u8x3/" + sizeName(s) + "/gpu/resident/";
    const auto reg = [&](const std::string& tail, lp::gl::GpuMergeShape shape, bool projected) {
      benchmark::RegisterBenchmark(
          (name + tail).c_str(),
          [=](benchmark::State& st) { mergeGpu(st, s, false, shape, projected); })
          ->UseRealTime()
          ->Unit(benchmark::kMicrosecond);
    };
    for (int parts : {1, 2, 4, 8, 16, 32})
      reg("parts:" + std::to_string(parts), {.rowParts = parts}, true);
    for (int group : {32, 64, 256})
      reg("group:" + std::to_string(group), {.groupSize = group}, true);
    reg("unprojected", {}, false);
    reg("bound:no-judgement", {.judge = false}, true);
  }
  for (Size s : {Size{1920, 1080}, Size{3840, 2160}})
    benchmark::RegisterBenchmark(("Render/bunny/" + sizeName(s) + "/msaa:4").c_str(),
                                 [=](benchmark::State& st) { renderBunny(st, s); })
        ->UseRealTime()
        ->Unit(benchmark::kMicrosecond);
  for (Size s : {Size{300, 300}, Size{1920, 960}, Size{3840, 1920}})
    for (const auto& [bg, name] : {std::pair{MergedBackground::None, "merge"},
                                   {MergedBackground::Kept, "merge/background"},
                                   {MergedBackground::ReadBack, "merge/background:readback"}})
      benchmark::RegisterBenchmark(
          ("Frame/u8x3/" + sizeName(s) + "/" + name + "/render:1920x1080").c_str(),
          [=, bg = bg](benchmark::State& st) { frameLoopMerge(st, s, bg); })
          ->UseRealTime()
          ->Unit(benchmark::kMicrosecond);
  for (bool overlapped : {false, true})
    benchmark::RegisterBenchmark((std::string("Frame/u8/3840x1920/render:1920x1080/") +
                                  (overlapped ? "overlapped" : "serial"))
                                     .c_str(),
                                 [=](benchmark::State& st) {
                                   frameLoop(st, {3840, 1920}, overlapped);
                                 })
        ->UseRealTime()
        ->Unit(benchmark::kMicrosecond);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  try {
    std::fprintf(stderr, "liveprobe-gpu-bench: %s\n", context().describe().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "liveprobe-gpu-bench: %s\n", e.what());
    return 1;
  }
  benchmark::AddCustomContext("gl", context().describe());
  benchmark::AddCustomContext("gl_multiprocessors", multiprocessors());
  registerAll();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return gMismatch ? 1 : 0;
}
