#pragma once
// What the app hands to GL: the context it opens, the model, the lighting and the background.
#include <memory>
#include <utility>

#include "environment.h"
#include "liveprobe/capture/processed_frame.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/gl/mesh.h"
#include "liveprobe/gl/renderer.h"
#include "settings.h"

namespace lp::cli {

/// The background the frame path made (liveprobe/capture/processed_frame.h); none when empty.
void setBackground(gl::Renderer& r, const Background& background);

gl::Backend glBackend(const SceneSettings& s);

/// Creates a GL context (lp::Error on failure); `headlessSize`, where given, is its size when
/// Auto finds no display; `gpu`, an EGL device (--gpu). Whether it is headless is the context's
/// to say (isHeadless()).
std::unique_ptr<gl::GlContext> openContext(gl::Backend backend, std::pair<int, int> size,
                                           std::pair<int, int> headlessSize = {0, 0}, int gpu = -1);

/// Uploads the mesh and its albedo texture.
void loadModel(gl::Renderer& r, const Mesh& mesh);

/// Uploads the lighting, its orientation and its background.
void loadLighting(gl::Renderer& r, const Lighting& lighting);

}  // namespace lp::cli
