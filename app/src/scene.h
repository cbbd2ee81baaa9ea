#pragma once
// What render, view and replay share from the command line: the scene's options (model, camera,
// look, GL context, lighting and layout: scene_options.cpp), and the model, camera and shading
// they give. The lighting itself: environment.h; what goes to GL: scene_gl.h.
#include <optional>
#include <string>
#include <vector>

#include "args.h"
#include "liveprobe/gl/mesh.h"
#include "liveprobe/gl/renderer.h"
#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/sh.h"
#include "settings.h"

/// What a stream command's SOURCE may be, for the commands' help.
#define LP_SOURCE_KINDS                                                                        \
  "a video, an image sequence (a folder, or a frame-number pattern like frames/%04d.png), an " \
  "image, a folder of six cube faces, synthetic[:WxH[@FPS]], or a URL (http(s)://, rtsp://, "  \
  "srt://, ...: a file or a stream on a server)"

namespace lp::cli {

/// Options for the model, camera and look (appended to a command's own).
std::vector<OptionSpec> sceneOptions();
/// --gl and --gpu: which GL context draws (part of sceneOptions(); bench takes them alone).
std::vector<OptionSpec> glOptions(const std::string& group);
/// Options choosing the lighting: --env and the layout options, --coeffs, --coeff.
std::vector<OptionSpec> lightingOptions();
/// --layout, --circle, --fov, and the environment's orientation (--env-rotate, --env-flip).
std::vector<OptionSpec> layoutOptions();
/// --model FILE|sphere (default sphere), fitted to the unit sphere. Throws lp::Error.
Mesh meshFrom(const SceneSettings& s);
gl::Camera cameraFrom(const SceneSettings& s);
/// --exposure X|auto (default auto: the environment's mean radiance maps to 0.18), --tonemap,
/// --no-background.
gl::ShadingSettings shadingFrom(const SceneSettings& s, const Sh9& radiance,
                                bool environment = true, const std::vector<Light>& lights = {});

/// The automatic exposure. With an environment (a background to match): the photographic rule,
/// the mean radiance (L00 Y00, luminance) maps to 0.18. Without one (coefficients only), from the
/// irradiance itself: the brightest white diffuse surface (max over n of Y(E(n)) / pi) maps to
/// 1.0, so any set of coefficients, a single one included, is visible. 1 if all is dark.
float autoExposure(const Sh9& radiance, bool environment = true,
                   const std::vector<Light>& lights = {});
}  // namespace lp::cli
