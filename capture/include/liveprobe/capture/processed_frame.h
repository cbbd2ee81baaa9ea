#pragma once
// One frame as the capture pipeline hands it on (liveprobe/capture/pipeline.h): its coefficients
// and lights, what to draw behind the model, its stage times and its confidence. Its own header:
// what reads a frame's record (liveprobe/exchange) needs this, not the pipeline that makes it.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "liveprobe/capture/image.h"
#include "liveprobe/capture/stages.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/frame/frame_confidence.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/sh.h"

namespace lp::gl {
class GpuImage;  // liveprobe/gl/gpu_image.h: named here, never included (capture knows no GL)
}

namespace lp {

/// Where a frame's coefficients were summed: on the CPU (the frame path's projector, or a
/// bracket's merge), or on the GPU (FrameRequest::projectWith). The one way the frame path says it.
enum class ProjectedOn : std::uint8_t { Cpu, Gpu };

/// "cpu", "gpu".
const char* projectedOnName(ProjectedOn on);

/// The GPU's own time of a frame's GL work (ms), by timer queries read a few frames late, so each
/// is an earlier frame's: none where the context has no GPU timer (a software rasterizer answers
/// 0), where the work was not on the GPU, or before the first reading. Never 0.
struct GpuTimes {
  std::optional<double> upload, project, merge, render;
  /// Each time's record key and member, in the order of the frame's stages.
  static constexpr std::array<std::pair<const char*, std::optional<double> GpuTimes::*>, 4> kTimes =
      {{{"gpu_upload", &GpuTimes::upload},
        {"gpu_project", &GpuTimes::project},
        {"gpu_merge", &GpuTimes::merge},
        {"gpu_render", &GpuTimes::render}}};
};

/// The frame as the display draws it behind the model, made once for every caller
/// (FrameProcessor::run): the frame itself where the display decodes it (8-bit sRGB in a layout
/// GL draws as it is), else its linear copy in radiance units, resampled to equirect where GL
/// does not draw the layout (cube, mirror ball, fisheye).
struct Background {
  std::shared_ptr<const Frame> raw;    ///< the frame as captured; the GPU decodes sRGB
  std::shared_ptr<const Image> image;  ///< or the linear copy
  /// Or a bracket's merged radiance kept on the GPU that merged it (GpuWork::mergedImage), for a
  /// display whose context shares that one's objects; its size beside it.
  std::shared_ptr<const gl::GpuImage> onGpu;
  int onGpuWidth = 0, onGpuHeight = 0;
  Layout layout = Layout::Equirect;  ///< as drawn: equirect or angular
  /// `raw`, `onGpu`: the linear scale of its values (the exposure). `image` made from an 8-bit
  /// frame: the scale its values carry, so the display can show it as the source looks
  /// (gl::Renderer::setBackground); 0 for HDR frames.
  float scale = 0.0f;

  bool empty() const { return !raw && !image && !onGpu; }
  int width() const { return raw ? raw->width : image ? image->width : onGpuWidth; }
  int height() const { return raw ? raw->height : image ? image->height : onGpuHeight; }
};

struct ProcessedFrame {
  std::uint64_t index = 0;     ///< position in this pipeline's output, from 0
  std::uint64_t sequence = 0;  ///< the source's frame number
  std::size_t reconnects = 0;  ///< times the source had reopened its stream when it sent this
  int width = 0, height = 0;   ///< the source frame's size (a merged bracket's: its frames')
  double timestamp = 0;        ///< the source's timestamp, seconds
  Sh9 radiance;    ///< after orientation and smoothing (with lights: the residual, the sky)
  Sh9 unsmoothed;  ///< after orientation, before smoothing
  /// With PipelineOptions::lights: the dominant compact lights (liveprobe/sh/lights.h), after
  /// orientation and smoothing, beside the residual `radiance`.
  std::vector<Light> lights;
  Background background;  ///< when PipelineOptions::keepImages
  StageTimes times;       ///< capture's stages; the viewer adds its own
  std::size_t saturated = 0;
  /// How far this frame's lighting can be trusted (clipped power, the bracket's agreement).
  FrameConfidence confidence;
  /// The confidence was below PipelineOptions::holdBelow: the lighting is the last good frame's.
  bool held = false;
  /// Where glass-to-light latency starts, CLOCK_MONOTONIC seconds: the driver's capture time
  /// for a camera, the moment the frame was grabbed for a file.
  double captureTime = 0;
  /// Capture to coefficients ready, ms.
  double coefficientsLatencyMs = 0;
  /// A followed mirror ball (PipelineOptions::followBall): the circle (centre x, y, radius in
  /// pixels) this frame was projected with, and whether the ball was lost in it (the last circle).
  std::optional<glm::vec3> ball;
  bool ballLost = false;
  ProjectedOn projectedOn = ProjectedOn::Cpu;
  bool mergedOnGpu = false;  ///< a bracket merged (and projected, where in one pass) on the GPU
  GpuTimes gpu;  ///< capture's: the projection's and the merge's (the viewer adds the upload's
                 ///< and the render's)
};

}  // namespace lp
