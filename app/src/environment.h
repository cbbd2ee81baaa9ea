#pragma once
// The lighting a still command draws with: an environment map in any layout, oriented by
// --env-rotate and --env-flip, taken through the frame path; or coefficients from --coeffs or
// --coeff.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "liveprobe/capture/ball.h"
#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/capture/lens.h"
#include "liveprobe/capture/processed_frame.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/sh.h"
#include "settings.h"

namespace lp::cli {

/// --env-rotate YAW,PITCH,ROLL and --env-flip as one orthogonal matrix O: a light at file
/// direction d lies in world direction O d, with O = Rz(yaw) Ry(pitch) Rx(roll) * F, F the
/// flip z -> -z (a panorama stored upside down) or the identity. Identity when neither is given.
glm::mat3 envOrientation(const PanoramaSettings& p);
/// The layout options as a spec (option errors are reported before any file is read). A source
/// that knows its own layout (six cube faces) gives the default, and a --layout that contradicts
/// it is refused. `findsBall`: the caller finds the ball of --circle auto (one image: ballCircle;
/// a stream: PipelineOptions::followBall), and the circle (and the traced ball's lens) is left
/// unset; otherwise --circle auto is refused.
LayoutSpec layoutSpec(const PanoramaSettings& p, const FrameSource* source = nullptr,
                      bool findsBall = false);
/// Where --circle auto searches a W x H frame of the calibrated `camera`: the square inside its
/// image circle (a fisheye's, black around it, a stronger circle than any ball); none where the
/// lens sees the whole frame.
std::optional<FrameWindow> ballSearchWindow(const LensCalibration& camera, int width, int height);
/// --circle auto: `spec` with the circle of the ball found in `frame` (and the traced ball's lens
/// for it, with --lens), said in one line. Throws lp::Error naming `source` when there is none.
void ballCircle(LayoutSpec& spec, const PanoramaSettings& p, const Frame& frame,
                const std::string& source);

/// A still environment in any layout: FILE is an image, or a folder of six cube faces.
struct Environment {
  /// Linear radiance, in the file's layout (what reads pixels: the brute force, the glTF cube).
  std::shared_ptr<const Image> linear;
  const Image& image() const { return *linear; }
  Background background;  ///< as the display draws it, when asked (FrameProcessor::run)
  LayoutSpec layout;
  glm::mat3 orientation{1.0f};  ///< world from file (envOrientation)
  Sh9 radiance;                 ///< unwindowed, turned by `orientation` (with lights: the rest)
  std::vector<Light> lights;    ///< the dominant compact lights, when asked, turned likewise
  Sh9 whole;                    ///< the whole map's coefficients, lights included
  double projectMs = 0;         ///< the frame path's time for it (its tables made beforehand)
  double coverage = 1;          ///< the share of the sphere the frame measures (Projector)
  ProjectedOn projectedOn = ProjectedOn::Cpu;
};
/// Reads the first frame of `source` and takes it through the frame path (FrameProcessor: one
/// projection, the lights split out when `lights` asks), in the layout and orientation the
/// options give (layoutSpec, envOrientation), with the display's background when `background`
/// asks, projected by `projectWith` where given (the GPU's, FrameRequest::projectWith). Warns
/// (one line) about a likely layout mistake. Throws lp::Error naming the source.
Environment loadEnvironment(const std::string& source, const PanoramaSettings& p,
                            const LightOptions& lights = {.maxLights = 0}, bool background = false,
                            const std::function<Sh9(const ProjectionJob&)>& projectWith = {});

/// One warning line when the frame's shape suggests another layout than the one in use: a square
/// image or a 16:9 frame taken as equirect by default (`given`: --layout named it, and the shape
/// is the user's to know), or an angular map or fisheye frame whose corners are not black.
void warnIfLayoutLooksWrong(const std::string& source, const LayoutSpec& layout, bool given,
                            int width, int height, const float* rgb = nullptr);

struct Lighting {
  Sh9 radiance;
  std::vector<Light> lights;  ///< --sun with --env, or the "lights" of a --coeffs file
  Background background;      ///< the environment, when lighting came from one
  LayoutSpec layout;
  glm::mat3 orientation{1.0f};
  ProjectedOn projectedOn = ProjectedOn::Cpu;  ///< an --env map's
};

/// From --env FILE [--layout], --coeffs FILE.json or --coeff NAME=VALUE...; nullopt if none given.
/// An --env map is projected by `projectWith` where given (loadEnvironment).
std::optional<Lighting> lightingFrom(
    const Settings& s, const std::function<Sh9(const ProjectionJob&)>& projectWith = {});

/// "L20=-0.2" or "L22=0.1,0.2,0.3" (--coeff). Throws lp::Error on an unknown name or bad value.
CoeffAssignment parseCoeffAssignment(const std::string& text);

}  // namespace lp::cli
