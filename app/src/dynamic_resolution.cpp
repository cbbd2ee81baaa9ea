#include "dynamic_resolution.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lp::cli {

namespace {
constexpr float kMinScale = 0.3f;  // below this the model is a blur
constexpr int kSettleFrames = 8;   // the smoothed time follows a change within about this
}  // namespace

DynamicResolution::DynamicResolution(bool active, double targetMs)
    : active_(active), targetMs_(targetMs) {}

gl::ShadingSettings DynamicResolution::apply(gl::ShadingSettings s) const {
  if (!active_) return s;
  s.renderScale = scale_;
  if (msaaOff_) s.samples = 1;
  return s;
}

void DynamicResolution::update(double frameMs) {
  if (!active_ || !(frameMs > 0)) return;
  ema_ = ema_ == 0 ? frameMs : 0.8 * ema_ + 0.2 * frameMs;
  if (cooldown_ > 0) {
    --cooldown_;
    return;
  }
  if (ema_ > 1.1 * targetMs_) {
    // Too slow: first MSAA goes, then pixels, by the step the time asks for (the cost of the
    // view grows with its pixels, the scale squared), at most a quarter at once.
    if (!msaaOff_) {
      msaaOff_ = true;
    } else if (scale_ > kMinScale) {
      const float step = std::clamp(float(std::sqrt(targetMs_ / ema_)), 0.75f, 0.95f);
      scale_ = std::max(kMinScale, scale_ * step);
    } else {
      return;
    }
    cooldown_ = kSettleFrames;
  } else if (ema_ < 0.65 * targetMs_ && scale_ < 1.0f) {
    scale_ = std::min(1.0f, scale_ * 1.08f);
    cooldown_ = kSettleFrames;
  }
}

std::string DynamicResolution::describe() const {
  if (!active_) return {};
  char text[96];
  std::snprintf(text, sizeof text, "software GL: 3D view at %.0f%%%s", 100.0 * scale_,
                msaaOff_ ? ", no MSAA" : "");
  return text;
}

}  // namespace lp::cli
