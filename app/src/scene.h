#pragma once
// What render, view and replay share: lighting, model, camera and shading from the command line.
#include <optional>
#include <string>
#include <vector>

#include "args.h"
#include "capture/image.h"
#include "capture/layout.h"
#include "shading/gl/context.h"
#include "shading/gl/renderer.h"
#include "shading/mesh.h"
#include "shading/sh.h"

namespace lp::cli {

/// Options for the model, camera and look (appended to a command's own).
std::vector<OptionSpec> sceneOptions();
/// Options choosing the lighting: --env/--layout, --coeffs, --coeff.
std::vector<OptionSpec> lightingOptions();

struct Lighting {
  Sh9 radiance;
  std::optional<Image> background;  ///< the environment, when lighting came from one
  Layout layout = Layout::Equirect;
};

/// From --env FILE [--layout], --coeffs FILE.json or --coeff NAME=VALUE...; nullopt if none given.
std::optional<Lighting> lightingFromArgs(const Args& a);

/// "L20=-0.2" or "L22=0.1,0.2,0.3" into `sh`. Throws lp::Error on an unknown name or bad value.
void applyCoeffAssignment(const std::string& text, Sh9& sh);

/// --model FILE|sphere (default sphere), fitted to the unit sphere. Throws lp::Error.
Mesh meshFromArgs(const Args& a);
gl::Camera cameraFromArgs(const Args& a);
/// --exposure X|auto (default auto: the environment's mean radiance maps to 0.18), --tonemap,
/// --no-background.
gl::ShadingSettings shadingFromArgs(const Args& a, const Sh9& radiance);

/// Exposure that maps the mean radiance of `radiance` (L00 Y00, luminance) to 0.18; 1 if dark.
float autoExposure(const Sh9& radiance);
gl::Backend backendFromArgs(const Args& a);

/// Uploads mesh (and its albedo texture), lighting and background into `r`.
void loadScene(gl::Renderer& r, const Mesh& mesh, const Lighting& lighting);

/// Orbit and zoom from mouse input.
void applyInput(gl::Camera& camera, const gl::InputDelta& input);

}  // namespace lp::cli
