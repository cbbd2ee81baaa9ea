#pragma once
// The one frame path: a Frame in, the frame's whole result out (run()): its lighting, the
// background the display draws, and the stage times. Every caller (the capture pipeline, bench,
// the still commands, the accuracy evaluation) goes through it, so a frame is taken one way: the
// frame as a panorama view, the exposure applied once (an 8-bit frame's lookup table carries the
// photometry's exposure, a float frame is scaled after the projection, which is linear, and
// Frame::radianceScale scales both), an optional area-averaged reduction, the coefficients and
// the lights, then the orientation; and the background as the frame itself where the display
// decodes it, or a linear copy resampled where GL does not draw the layout.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "liveprobe/capture/image.h"
#include "liveprobe/capture/photometry.h"
#include "liveprobe/capture/processed_frame.h"
#include "liveprobe/capture/stages.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/frame/frame_confidence.h"
#include "liveprobe/sh/executor.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/projector.h"
#include "liveprobe/sh/sh.h"

namespace lp {

struct FrameProcessorOptions {
  LayoutSpec layout;
  Photometry photometry;
  /// World from file (the environment's orientation); none: the identity.
  std::optional<glm::mat3> rotation;
  int reduce = 1;  ///< equirect: project an F x F area average of the frame (1: the frame)
  LightOptions lights{.maxLights = 0};  ///< maxLights = 0 (the default): coefficients only
};

/// One frame's lighting in the world frame, in linear radiance units.
struct FrameLighting {
  Sh9 radiance;               ///< with lights: the rest of the map (the lights' pixels filled)
  std::vector<Light> lights;  ///< the dominant compact lights, when asked for
  Sh9 whole;                  ///< the whole map's coefficients, lights included
};

/// What run() makes besides the lighting.
struct FrameRequest {
  bool background = false;  ///< the display's background (Background)
  bool linear = false;      ///< the linear frame in its own layout (the brute force, exports)
  bool saturation = false;  ///< count the values at 255 (a linear copy counts them anyway)
  /// Where the coefficients come from, when not from the CPU's projection here. `projected`: the
  /// coefficients of the frame's own pixels, projected as it was made (a bracket merged and
  /// projected in one pass, liveprobe/hdr/merge.h); they are scaled and turned as the CPU's are.
  std::optional<Sh9> projected;
  /// With `projected`, where lights are asked for: the frame's row peaks as Projector::project
  /// makes them (MergeProjection::rowPeaks), from which the light search reads the frame's pixels
  /// here as the CPU path's does. Without them lights cannot be searched (lp::Error).
  const std::vector<float>* projectedPeaks = nullptr;
  /// `projectWith`: the GPU's projection (liveprobe/gl/gpu_projector.h), given the frame as the
  /// projection reads it; timed as the Project stage. Where lights are asked for it gives the row
  /// peaks too, and the light search reads the frame's pixels here as the CPU path's does.
  std::function<Sh9(const ProjectionJob&)> projectWith;
  /// Where the linear copy goes: a buffer of the caller's that nothing else reads any more (bench
  /// reuses one from frame to frame); none: a new one, as a frame handed to another thread needs.
  std::shared_ptr<Image> linearInto = nullptr;
};

/// A frame's whole result.
struct FrameResult {
  FrameLighting lighting;
  Background background;  ///< when asked
  /// When asked: the frame in linear radiance (Frame::radianceScale and the photometry applied)
  /// in its own layout.
  std::shared_ptr<const Image> linear;
  std::size_t saturated = 0;  ///< channel values at 255 (with a linear copy, or when asked)
  StageTimes times;           ///< Convert, Project and Resample, where they ran
  ProjectedOn projectedOn = ProjectedOn::Cpu;
  std::optional<double> gpuProjectMs;  ///< ProjectionJob::gpuMs, where it said one
};

class FrameProcessor {
 public:
  explicit FrameProcessor(FrameProcessorOptions options);
  ~FrameProcessor();
  FrameProcessor(FrameProcessor&&) noexcept;
  FrameProcessor& operator=(FrameProcessor&&) noexcept;

  /// The frame's lighting, and what `request` asks for besides: the one call every caller makes
  /// for a frame. The background is the frame itself (shared, not copied) where the display takes
  /// it as it is (displayTakesFrameAsIs), else a linear copy, resampled to equirect where GL
  /// does not draw the layout. Throws as process() does.
  FrameResult run(std::shared_ptr<const Frame> frame, const FrameRequest& request = {},
                  Executor* executor = nullptr);

  /// The lighting of `frame` alone. `linear`, when the caller has it, is the frame already
  /// converted by linearizer() (a reduction reads it instead of converting again). Throws lp::Error
  /// (without a source name: the caller adds it) when the frame does not fit the layout or the
  /// reduction, or when its coefficients are not finite. A processor is one stream's: the lights
  /// a frame gives hold the next frame's at the threshold (LightOptions::held).
  FrameLighting process(const Frame& frame, Executor* executor = nullptr,
                        const Image* linear = nullptr);

  /// How far one frame's lighting (from process()) can be trusted: an 8-bit frame's pixels with
  /// a channel at 255 are clipped, their power (by solid angle) a lower bound against the whole
  /// map's (from L00), and then the brightest source is not known to be measured. Reads only the
  /// clipped pixels. Float frames: full confidence.
  FrameConfidence confidence(const Frame& frame, const FrameLighting& lighting) const;

  /// Makes the projector (and the light index) for frames of `frame`'s size, as the first
  /// process() of that size would: a caller that times process() calls it first. Throws lp::Error
  /// as process() does for a frame that does not fit.
  void fit(const Frame& frame);

  /// Projects the next frames through `layout` (a followed ball's new circle): the projector is
  /// made again at the next frame; the stream's state (the lights held) is kept.
  void setLayout(LayoutSpec layout);

  /// The projector of the last frame's size (nullptr before the first frame).
  const Projector* projector() const;
  const Linearizer& linearizer() const { return linearizer_; }
  const FrameProcessorOptions& options() const { return opt_; }

 private:
  /// The frame as the projection reads it and the scale its coefficients take afterwards. Valid
  /// until the next call.
  struct ProjectedView {
    PanoramaView view;
    float scale = 1.0f;
  };
  ProjectedView view(const Frame& frame, const Image* linear = nullptr);
  /// The scale the coefficients of `frame`'s own pixels take (Frame::radianceScale, and for a
  /// float frame the photometry's exposure).
  float projectionScale(const Frame& frame) const;
  /// The lighting from coefficients projected elsewhere, scaled and turned as process()'s.
  FrameLighting fromProjected(const Sh9& whole, float scale) const;
  /// The lights split out of a projected frame (where asked), scaled and turned: the end of
  /// process() and of a projection of the caller's.
  FrameLighting split(const PanoramaView& view, const Sh9& whole, const std::vector<float>& peaks,
                      float scale);
  /// Scale, finiteness and orientation: the end of process() and fromProjected().
  FrameLighting finish(Sh9 whole, LightSplit split, float scale) const;
  FrameProcessorOptions opt_;
  Linearizer linearizer_;
  // On the heap: the extractor points at the projector, and both survive a move.
  std::unique_ptr<Projector> projector_;
  std::unique_ptr<LightExtractor> extractor_;
  Image converted_, reduced_;   ///< a reduction's buffers, kept from frame to frame
  std::uint64_t tablesId_ = 0;  ///< counts the projectors made (ProjectionJob::tablesId)
};

/// Whether the display takes this frame as it is: 8-bit sRGB in a layout the background shader
/// draws directly (equirect, angular). Then no linear copy is made for it; the GPU decodes sRGB.
bool displayTakesFrameAsIs(const Frame& frame, const Photometry& photometry,
                           const LayoutSpec& layout);

}  // namespace lp
