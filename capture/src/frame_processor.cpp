#include "liveprobe/capture/frame_processor.h"

#include <cmath>
#include <cstring>
#include <numbers>

#include "liveprobe/capture/resample.h"
#include "liveprobe/sh/error.h"

namespace lp {

const char* projectedOnName(ProjectedOn on) { return on == ProjectedOn::Gpu ? "gpu" : "cpu"; }

bool displayTakesFrameAsIs(const Frame& frame, const Photometry& photometry,
                           const LayoutSpec& layout) {
  return frame.format == PanoramaFormat::BgrU8 && photometry.gamma == 0.0f &&
         displayDrawsAsIs(layout);
}

FrameProcessor::FrameProcessor(FrameProcessorOptions options)
    : opt_(std::move(options)), linearizer_(opt_.photometry) {
  setLayout(std::move(opt_.layout));
}

void FrameProcessor::setLayout(LayoutSpec layout) {
  opt_.layout = std::move(layout);
  // The ground of the unseen fill lies below the world's horizon, whatever the turn.
  if (opt_.rotation) opt_.layout.unseen.up = glm::transpose(*opt_.rotation) * glm::vec3(0, 0, 1);
  extractor_.reset();
  projector_.reset();
}
FrameProcessor::~FrameProcessor() = default;
FrameProcessor::FrameProcessor(FrameProcessor&&) noexcept = default;
FrameProcessor& FrameProcessor::operator=(FrameProcessor&&) noexcept = default;

const Projector* FrameProcessor::projector() const { return projector_.get(); }

void FrameProcessor::fit(const Frame& frame) {
  const int reduce = opt_.reduce;
  if (projector_ && projector_->width() * reduce == frame.width &&
      projector_->height() * reduce == frame.height)
    return;
  if (auto why = layoutMismatch(opt_.layout, frame.width, frame.height); !why.empty())
    throw Error(std::string(layoutName(opt_.layout.layout)) + " layout: " + why);
  if (reduce > 1 &&
      (opt_.layout.layout != Layout::Equirect || frame.width % reduce || frame.height % reduce))
    throw Error("a reduction by " + std::to_string(reduce) +
                " needs an equirect frame whose size is a multiple of it");
  extractor_.reset();
  projector_ =
      std::make_unique<Projector>(opt_.layout, frame.width / reduce, frame.height / reduce);
  ++tablesId_;
  if (opt_.lights.maxLights > 0) extractor_ = std::make_unique<LightExtractor>(*projector_);
}

FrameConfidence FrameProcessor::confidence(const Frame& frame, const FrameLighting& lit) const {
  FrameConfidence c;
  if (frame.format != PanoramaFormat::BgrU8 || !projector_) return c;
  auto luminance = [](float r, float g, float b) { return 0.2126 * r + 0.7152 * g + 0.0722 * b; };
  // The whole map's power: L00 = Y00 times the integral of the radiance.
  const Rgb& l00 = lit.whole.c[0];
  const double total = luminance(l00[0], l00[1], l00[2]) / double(kY00);
  // The clipped pixels' power, by the projector's solid angles (an equirect formula when the
  // projection was of a reduced frame).
  const auto& samples = projector_->samples();
  const bool own = samples.size() == std::size_t(frame.width) * std::size_t(frame.height);
  const auto& lut = linearizer_.table();
  const double row = 2.0 * std::numbers::pi / frame.width * std::numbers::pi / frame.height;
  const std::uint8_t* data = frame.bgr8.data();
  const std::uint8_t* end = data + frame.bgr8.size();
  double clipped = 0;
  for (const std::uint8_t* p = data; p < end && (p = static_cast<const std::uint8_t*>(
                                                     std::memchr(p, 255, std::size_t(end - p))));) {
    const std::size_t px = std::size_t(p - data) / 3;
    const std::uint8_t* q = data + px * 3;
    const double solidAngle =
        own ? samples[px].solidAngle
            : row * std::sin(std::numbers::pi * (double(px / std::size_t(frame.width)) + 0.5) /
                             frame.height);
    clipped += luminance(lut[q[2]], lut[q[1]], lut[q[0]]) * solidAngle;
    c.brightestMeasured = false;
    p = q + 3;
  }
  clipped *= frame.radianceScale;
  c.clippedShare = total > 0 ? std::min(1.0, clipped / total) : 0.0;
  return c;
}

float FrameProcessor::projectionScale(const Frame& frame) const {
  // An 8-bit frame's lookup table carries the photometry's exposure; a float frame is scaled
  // after its projection.
  const float scale = float(frame.radianceScale);
  return frame.format == PanoramaFormat::BgrU8 ? scale : scale * linearizer_.exposure();
}

FrameProcessor::ProjectedView FrameProcessor::view(const Frame& frame, const Image* linear) {
  fit(frame);
  // An 8-bit frame through the lookup table (the photometry's exposure in it) inside the
  // projection; a float frame as it is, scaled after; a reduction reads the linear copy.
  const float scale = float(frame.radianceScale);
  if (opt_.reduce > 1) {
    if (!linear) {
      linearizer_.convert(frame, converted_);
      linear = &converted_;
    }
    reduceEquirect(linear->rgb.data(), linear->width, linear->height, opt_.reduce, reduced_);
    return {PanoramaView::rgbF32(reduced_.rgb.data(), reduced_.width, reduced_.height,
                                 projector_->spec()),
            scale};
  }
  if (frame.format == PanoramaFormat::BgrU8)
    return {PanoramaView::bgrU8(frame.bgr8.data(), frame.width, frame.height,
                                linearizer_.table().data(), projector_->spec()),
            projectionScale(frame)};
  return {PanoramaView::rgbF32(frame.rgb.data(), frame.width, frame.height, projector_->spec()),
          projectionScale(frame)};
}

FrameResult FrameProcessor::run(std::shared_ptr<const Frame> frame, const FrameRequest& request,
                                Executor* executor) {
  StageClock clock;
  FrameResult r;
  const Frame& f = *frame;
  // A linear copy where something reads it (a reduction reads it too, before the frame's
  // radianceScale: the projection applies that once); none for a background the display decodes.
  const bool asIs = request.background && displayTakesFrameAsIs(f, opt_.photometry, opt_.layout);
  std::shared_ptr<Image> linear;
  if (request.linear || (request.background && !asIs)) {
    linear = request.linearInto ? request.linearInto : std::make_shared<Image>();
    r.saturated = linearizer_.convert(f, *linear);
  } else if (request.saturation) {
    r.saturated = countSaturated(f);
  }
  clock.lap(Stage::Convert);
  if (request.projected && opt_.lights.maxLights > 0 && request.projectedPeaks) {
    // Projected as it was made; the light search is this stage's.
    const ProjectedView v = view(f, linear.get());
    r.lighting = split(v.view, *request.projected, *request.projectedPeaks, v.scale);
    clock.lap(Stage::Project);
  } else if (request.projected) {
    // Projected as it was made: its time is that stage's (a merge's), not this one's.
    r.lighting = fromProjected(*request.projected, projectionScale(f));
    clock.skip();
  } else {
    if (request.projectWith) {
      const ProjectedView v = view(f, linear.get());
      std::vector<float> peaks;
      const Sh9 whole = request.projectWith(
          {v.view, *projector_, tablesId_, extractor_ ? &peaks : nullptr, &r.gpuProjectMs});
      r.lighting = split(v.view, whole, peaks, v.scale);
      r.projectedOn = ProjectedOn::Gpu;
    } else {
      r.lighting = process(f, executor, linear.get());
    }
    clock.lap(Stage::Project);
  }
  const float scale = float(f.radianceScale);
  if (linear && scale != 1.0f) {
    for (float& v : linear->rgb) v *= scale;
    clock.lap(Stage::Convert);
  }
  if (request.background) {
    Background& b = r.background;
    b.layout = displayLayout(opt_.layout);
    const float decoded = scale * opt_.photometry.exposure;
    if (asIs) {
      b.raw = std::move(frame);
      b.scale = decoded;
    } else {
      b.scale = f.format == PanoramaFormat::BgrU8 ? decoded : 0.0f;
      if (displayDrawsAsIs(opt_.layout)) {
        b.image = linear;
      } else {
        b.image = std::make_shared<Image>(displayEquirect(*linear, opt_.layout));
        clock.lap(Stage::Resample);
      }
    }
  }
  if (request.linear) r.linear = std::move(linear);
  r.times = clock.times;
  return r;
}

FrameLighting FrameProcessor::process(const Frame& frame, Executor* executor, const Image* linear) {
  const ProjectedView v = view(frame, linear);
  std::vector<float> peaks;
  const Sh9 whole = projector_->project(v.view, executor, extractor_ ? &peaks : nullptr);
  return split(v.view, whole, peaks, v.scale);
}

FrameLighting FrameProcessor::split(const PanoramaView& view, const Sh9& whole,
                                    const std::vector<float>& peaks, float scale) {
  LightSplit parts;
  if (extractor_) {
    parts = extractor_->extract(view, whole, peaks, opt_.lights);
    // The next frame's hysteresis: where this one's lights are, in the frame's orientation.
    opt_.lights.held.clear();
    for (const Light& l : parts.lights) opt_.lights.held.push_back(l.dir);
  } else
    parts.residual = whole;
  return finish(whole, std::move(parts), scale);
}

FrameLighting FrameProcessor::fromProjected(const Sh9& whole, float scale) const {
  if (opt_.lights.maxLights > 0)
    throw Error("lights are searched in the frame: project it with process()");
  LightSplit split;
  split.residual = whole;
  return finish(whole, std::move(split), scale);
}

FrameLighting FrameProcessor::finish(Sh9 whole, LightSplit split, float scale) const {
  FrameLighting out;
  out.whole = whole;
  if (scale != 1.0f) {
    out.whole *= scale;
    split.residual *= scale;
    for (Light& l : split.lights) l.power *= scale;
  }
  if (!isFinite(out.whole) || !isFinite(split.residual))
    throw Error("the coefficients are not finite (radiance too large to sum in float)");
  if (opt_.rotation) {
    split = rotateSplit(split, *opt_.rotation);
    out.whole = rotateSh(out.whole, *opt_.rotation);
  }
  out.radiance = split.residual;
  out.lights = std::move(split.lights);
  return out;
}

}  // namespace lp
