#pragma once
// Where frames are projected (--projection): one rule for every command. One frame's commands
// (render, view, bench) project in the context that draws (gl::GpuFrameProjection); a stream's
// capture thread in a headless EGL context of its own on the same device (a GL context is current
// on one thread).
#include <functional>
#include <memory>
#include <string>

#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/pipeline.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/gl/gpu_merge.h"
#include "liveprobe/gl/gpu_projector.h"
#include "liveprobe/gl/gpu_timer.h"
#include "settings.h"

namespace lp::cli {

/// Whether frames are projected on the GPU of `ctx` (current): `gpu` where asked (lp::Error in
/// one line where the context has no compute shaders), `auto` where the context is a GPU with
/// compute shaders (a software rasterizer projects slower than the CPU).
bool projectsOnGpu(ProjectOn asked, const gl::GlContext& ctx);

/// A stream's projection on the GPU (PipelineOptions::projectOnGpu), decided as projectsOnGpu()
/// decides for the capture thread's own context: a headless EGL context on the device that
/// `drawing` (current) draws on, made here and made current on the capture thread. A bracket is
/// merged there too (gl::GpuMerge). `gpu` where
/// `drawing` is not EGL (a window, OSMesa) is refused in one line; `auto` there is the CPU.
/// Returns none for the CPU; `used` says where frames go ("the GPU, EGL device 0 (...)").
std::function<GpuWork()> streamProjection(ProjectOn asked, gl::GlContext& drawing,
                                          std::string& used);

}  // namespace lp::cli
