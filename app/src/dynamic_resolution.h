#pragma once
// Dynamic resolution: a window drawn by a software rasterizer (Mesa's llvmpipe or softpipe,
// SwiftShader) keeps its frame rate by drawing the 3D view without MSAA, then at a lower internal
// resolution, from the frame times it measures; the HUD stays at full resolution and says so.
// On a GPU, and headless (where every frame is written at the size asked), nothing changes.
#include <string>

#include "liveprobe/gl/renderer.h"

namespace lp::cli {

class DynamicResolution {
 public:
  /// `active`: a window on a software GL. `targetMs`: the frame time to keep (30 frames/s).
  explicit DynamicResolution(bool active = false, double targetMs = 1000.0 / 30.0);

  bool active() const { return active_; }
  float scale() const { return scale_; }
  bool msaaOff() const { return msaaOff_; }
  /// The settings to draw with: `s` with the current scale, and without MSAA once frames were slow.
  gl::ShadingSettings apply(gl::ShadingSettings s) const;
  /// One drawn frame's time (draw and present), ms.
  void update(double frameMs);
  /// "software GL: 3D view at 52%, no MSAA"; empty when inactive.
  std::string describe() const;

 private:
  bool active_;
  double targetMs_;
  double ema_ = 0;    ///< the frame time, smoothed
  int cooldown_ = 0;  ///< frames to wait after a change before judging again
  float scale_ = 1.0f;
  bool msaaOff_ = false;
};

}  // namespace lp::cli
