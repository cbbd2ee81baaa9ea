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

std::function<std::function<Sh9(const ProjectionJob&)>()> streamProjection(ProjectOn asked,
                                                                           gl::GlContext& drawing,
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
  try {
    gl::releaseCurrentContext();  // (a GLX window's and an EGL one are not current together)
    // (A window's: the first GPU EGL finds, else its software device.)
    ctx = gl::createGlContext({gl::Backend::Egl, 16, 16, "capture", false, 0, 0,
                               drawing.backend() == gl::Backend::Egl ? drawing.device() : -1});
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
  return [ctx] {
    ctx->makeCurrent();
    // The passes and the frame's texture belong to the capture thread's context: deleted there,
    // before the context is let go (the last owner of `ctx` destroys it on its own thread).
    struct OnThread {
      std::shared_ptr<gl::GlContext> ctx;  ///< kept alive while the thread uses it
      std::unique_ptr<gl::GpuFrameProjection> projection =
          std::make_unique<gl::GpuFrameProjection>();
      std::unique_ptr<gl::GpuTimer> timer = std::make_unique<gl::GpuTimer>();
      bool hasTimer = false;  ///< a software rasterizer has none (its queries read ~0)
      ~OnThread() {
        projection.reset();
        timer.reset();
        gl::releaseCurrentContext();
      }
    };
    auto state = std::make_shared<OnThread>();
    state->ctx = ctx;
    state->hasTimer = !gl::isSoftwareRenderer(ctx->describe());
    return [state](const ProjectionJob& job) {
      gl::GpuTimer* timer = state->timer.get();
      timer->beginFrame();
      timer->begin(gl::GpuTimer::Project);
      const Sh9 whole = (*state->projection)(job);
      timer->end();
      const std::optional<double> ms = timer->ms(gl::GpuTimer::Project);
      if (job.gpuMs && state->hasTimer && ms && *ms > 0) *job.gpuMs = ms;
      return whole;
    };
  };
}

}  // namespace lp::cli
