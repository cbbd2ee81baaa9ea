#pragma once
// What render, view and replay share: lighting, model, camera and shading from the command line.
#include <optional>
#include <string>
#include <vector>

#include "args.h"
#include "liveprobe/capture/frame.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/gl/mesh.h"
#include "liveprobe/gl/renderer.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/sh.h"
#include "settings.h"

/// What a stream command's SOURCE may be, for the commands' help.
#define LP_SOURCE_KINDS                                                                        \
  "a video, an image sequence (a folder, or a frame-number pattern like frames/%04d.png), an " \
  "image, a folder of six cube faces, or synthetic[:WxH[@FPS]]"

namespace lp::cli {

/// Options for the model, camera and look (appended to a command's own).
std::vector<OptionSpec> sceneOptions();
/// --gl and --gpu: which GL context draws (part of sceneOptions(); bench takes them alone).
std::vector<OptionSpec> glOptions(const std::string& group);
/// Options choosing the lighting: --env and the layout options, --coeffs, --coeff.
std::vector<OptionSpec> lightingOptions();
/// --layout, --circle, --fov, and the environment's orientation (--env-rotate, --env-flip).
std::vector<OptionSpec> layoutOptions();
/// --env-rotate YAW,PITCH,ROLL and --env-flip as one orthogonal matrix O: a light at file
/// direction d lies in world direction O d, with O = Rz(yaw) Ry(pitch) Rx(roll) * F, F the
/// flip z -> -z (a panorama stored upside down) or the identity. Identity when neither is given.
glm::mat3 envOrientation(const PanoramaSettings& p);
/// The layout options as a spec (option errors are reported before any file is read). A source
/// that knows its own layout (six cube faces) gives the default, and a --layout that contradicts
/// it is refused.
LayoutSpec layoutSpec(const PanoramaSettings& p, const FrameSource* source = nullptr);

/// A still environment in any layout: FILE is an image, or a folder of six cube faces.
struct Environment {
  Image image;  ///< linear RGB, as stored in the file
  LayoutSpec layout;
  glm::mat3 orientation{1.0f};  ///< world from file (envOrientation)
  Sh9 radiance;                 ///< unwindowed, turned by `orientation` (with lights: the rest)
  std::vector<Light> lights;    ///< the dominant compact lights, when asked, turned likewise
  Sh9 whole;                    ///< the whole map's coefficients, lights included
  double projectMs = 0;         ///< the frame path's time for it (its tables made beforehand)
  float displayScale = 0.0f;    ///< an 8-bit file: the scale its decoded values carry; 0 for HDR
};
/// Reads the first frame of `source` and takes it through the frame path (FrameProcessor: one
/// projection, the lights split out when `lights` asks), in the layout and orientation the
/// options give (layoutSpec, envOrientation). Warns (one line) about a likely layout
/// mistake. Throws lp::Error naming the source.
Environment loadEnvironment(const std::string& source, const PanoramaSettings& p,
                            const LightOptions& lights = {.maxLights = 0});

/// One warning line when the frame's shape suggests another layout than the one in use: a square
/// image or a 16:9 frame taken as equirect by default (`given`: --layout named it, and the shape
/// is the user's to know), or an angular map or fisheye frame whose corners are not black.
void warnIfLayoutLooksWrong(const std::string& source, const LayoutSpec& layout, bool given,
                            int width, int height, const float* rgb = nullptr);

struct Lighting {
  Sh9 radiance;
  std::vector<Light> lights;        ///< --sun with --env, or the "lights" of a --coeffs file
  std::optional<Image> background;  ///< the environment, when lighting came from one
  LayoutSpec layout;
  glm::mat3 orientation{1.0f};
  float displayScale = 0.0f;  ///< see Environment
};

/// The background texture: a panorama in a layout GL draws as it is (equirect or angular;
/// liveprobe/capture/resample.h: displayLayout, displayEquirect for the others).
/// `displayScale`: see gl::Renderer::setBackground (0 for an HDR frame).
void setBackground(gl::Renderer& r, const Image& panorama, Layout drawn, float displayScale = 0.0f);
/// The background from an 8-bit sRGB frame the display takes as it is
/// (liveprobe/capture/frame_processor.h, displayTakesFrameAsIs), its decoded values times `scale`.
void setBackground(gl::Renderer& r, const Frame& frame, Layout drawn, float scale);

/// From --env FILE [--layout], --coeffs FILE.json or --coeff NAME=VALUE...; nullopt if none given.
std::optional<Lighting> lightingFrom(const Settings& s);

/// "L20=-0.2" or "L22=0.1,0.2,0.3" into `sh`. Throws lp::Error on an unknown name or bad value.
void applyCoeffAssignment(const std::string& text, Sh9& sh);

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
gl::Backend glBackend(const SceneSettings& s);

/// Creates a GL context (lp::Error on failure); `headlessSize`, where given, is its size when
/// Auto finds no display; `gpu`, an EGL device (--gpu). Whether it is headless is the context's
/// to say (isHeadless()).
std::unique_ptr<gl::GlContext> openContext(gl::Backend backend, std::pair<int, int> size,
                                           std::pair<int, int> headlessSize = {0, 0}, int gpu = -1);

/// Uploads the mesh and its albedo texture.
void loadModel(gl::Renderer& r, const Mesh& mesh);

/// Uploads the lighting, its orientation and its background (resampled to equirect where GL does
/// not draw its layout as it is).
void loadLighting(gl::Renderer& r, const Lighting& lighting);

}  // namespace lp::cli
