#include "gpu_projection.h"

#include "liveprobe/sh/error.h"

namespace lp::cli {

bool projectsOnGpu(ProjectOn asked, const gl::GlContext& ctx) {
  if (asked == ProjectOn::Cpu) return false;
  const bool compute = gl::hasCompute();
  if (asked == ProjectOn::Gpu && !compute)
    throw Error("--projection gpu: " + ctx.describe() + " has no compute shaders (GL 4.3)");
  return compute && (asked == ProjectOn::Gpu || !gl::isSoftwareRenderer(ctx.describe()));
}

std::function<GpuWork()> streamProjection(ProjectOn asked, gl::GlContext& drawing,
                                          std::string& used) {
  used = "the CPU";
  if (asked == ProjectOn::Cpu) return {};
  if (drawing.backend() == gl::Backend::OsMesa) {  // (its GL is not EGL's)
    if (asked == ProjectOn::Gpu)
      throw Error(std::string("--projection gpu: a stream is projected on the GPU in a headless "
                              "EGL context, and this run draws with ") +
                  drawing.describe() + " (give --gl egl, or --projection cpu)");
    return {};
  }
  // The capture thread's context, on the drawing context's device: made (and GL loaded) here,
  // then this thread's own made current again.
  std::shared_ptr<gl::GlContext> ctx;
  bool shared = false;
  try {
    gl::releaseCurrentContext();  // (a GLX window's and an EGL one are not current together)
    // The two contexts share objects where the drawing one is EGL's (headless, or a window's on
    // the window's display): the merged frame is drawn where it was merged. Else (a window's GLX
    // context shares nothing with EGL, a driver that will not share) the frames are read back,
    // and a window's capture context is the first GPU EGL finds, else its software device.
    gl::ContextSpec spec{.backend = gl::Backend::Egl,
                         .width = 16,
                         .height = 16,
                         .title = "capture",
                         .vsync = false,
                         .gpu = drawing.backend() == gl::Backend::Egl ? drawing.device() : -1,
                         .shareWith = &drawing};
    try {
      ctx = gl::createGlContext(spec);
      shared = true;
    } catch (const gl::ContextError&) {
      spec.shareWith = nullptr;
    }
    if (!ctx) ctx = gl::createGlContext(spec);
  } catch (const gl::ContextError& e) {
    drawing.makeCurrent();
    if (asked == ProjectOn::Gpu) throw Error(std::string("--projection gpu: ") + e.what());
    return {};
  }
  bool onGpu = false;
  try {
    onGpu = projectsOnGpu(asked, *ctx);
  } catch (...) {
    gl::releaseCurrentContext();
    drawing.makeCurrent();
    throw;
  }
  gl::releaseCurrentContext();
  drawing.makeCurrent();
  if (!onGpu) return {};
  used = "the GPU, " + ctx->describe();
  return [ctx, shared] {
    ctx->makeCurrent();
    // The passes and the frame's texture belong to the capture thread's context: deleted there,
    // before the context is let go (the last owner of `ctx` destroys it on its own thread).
    struct OnThread {
      std::shared_ptr<gl::GlContext> ctx;  ///< kept alive while the thread uses it
      std::unique_ptr<gl::GpuFrameProjection> projection =
          std::make_unique<gl::GpuFrameProjection>();
      std::unique_ptr<gl::GpuMerge> merge = std::make_unique<gl::GpuMerge>();
      /// One timer each (a timer's frames are its own calls).
      std::unique_ptr<gl::GpuTimer> timer = std::make_unique<gl::GpuTimer>(),
                                    mergeTimer = std::make_unique<gl::GpuTimer>();
      bool hasTimer = false;          ///< a software rasterizer has none (its queries read ~0)
      std::optional<double> mergeMs;  ///< the last merge's
      ~OnThread() {
        projection.reset();
        merge.reset();
        timer.reset();
        mergeTimer.reset();
        gl::releaseCurrentContext();
      }
      /// `work` timed as `stage` (a few frames late: the timer's latency).
      std::optional<double> timed(gl::GpuTimer& t, gl::GpuTimer::Stage stage,
                                  const std::function<void()>& work) const {
        t.beginFrame();
        t.begin(stage);
        work();
        t.end();
        const std::optional<double> ms = t.ms(stage);
        return hasTimer && ms && *ms > 0 ? ms : std::nullopt;
      }
    };
    auto state = std::make_shared<OnThread>();
    state->ctx = ctx;
    state->hasTimer = !gl::isSoftwareRenderer(ctx->describe());
    GpuWork work;
    work.project = [state](const ProjectionJob& job) {
      Sh9 whole;
      const auto ms = state->timed(*state->timer, gl::GpuTimer::Project,
                                   [&] { whole = (*state->projection)(job); });
      if (job.gpuMs && ms) *job.gpuMs = ms;
      return whole;
    };
    work.merge = [state](const merge::FrameInput& in, std::vector<merge::RowSums>& rows) {
      state->mergeMs =
          state->timed(*state->mergeTimer, gl::GpuTimer::Merge, [&] { (*state->merge)(in, rows); });
    };
    work.mergeTurns = true;
    work.mergeLuminance = [state](std::uint64_t key, float* into) {
      return state->merge->readLuminance(key, into);
    };
    work.mergeMs = [state] { return state->mergeMs; };
    if (shared) work.mergedImage = [state] { return state->merge->takeKeptImage(); };
    return work;
  };
}

}  // namespace lp::cli
