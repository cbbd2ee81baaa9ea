#pragma once
// Constructors of the concrete sources, for openSource().
#include <memory>
#include <string>

#include "liveprobe/capture/frame.h"

namespace lp {

std::unique_ptr<FrameSource> openSynthetic(int width, int height, double fps);
std::unique_ptr<FrameSource> openStill(const std::string& path, double fps);
std::unique_ptr<FrameSource> openCubeFaces(const std::string& dir, double fps);
std::unique_ptr<FrameSource> openSequence(const std::string& dirOrPattern, double fps);
std::unique_ptr<FrameSource> openVideo(const std::string& path);

}  // namespace lp
