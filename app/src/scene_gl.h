#pragma once
// What the app hands to GL: the context it opens, the model, the lighting and the background.
#include <memory>
#include <utility>

#include "environment.h"
#include "liveprobe/capture/frame.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/gl/context.h"
#include "liveprobe/gl/mesh.h"
#include "liveprobe/gl/renderer.h"
#include "settings.h"

namespace lp::cli {

/// The background texture: a panorama in a layout GL draws as it is (equirect or angular;
/// liveprobe/capture/resample.h: displayLayout, displayEquirect for the others).
/// `displayScale`: see gl::Renderer::setBackground (0 for an HDR frame).
void setBackground(gl::Renderer& r, const Image& panorama, Layout drawn, float displayScale = 0.0f);
/// The background from an 8-bit sRGB frame the display takes as it is
/// (liveprobe/capture/frame_processor.h, displayTakesFrameAsIs), its decoded values times `scale`.
void setBackground(gl::Renderer& r, const Frame& frame, Layout drawn, float scale);

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
