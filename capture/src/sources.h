#pragma once
// Constructors of the concrete sources, for openSource().
#include <memory>
#include <optional>
#include <string>

#include "liveprobe/capture/open_source.h"
#include "liveprobe/frame/frame.h"

namespace lp {

std::unique_ptr<FrameSource> openSynthetic(int width, int height, double fps);
std::unique_ptr<FrameSource> openStill(const std::string& path, double fps);
std::unique_ptr<FrameSource> openCubeFaces(const std::string& dir, double fps);
std::unique_ptr<FrameSource> openSequence(const std::string& dirOrPattern, double fps);
std::unique_ptr<FrameSource> openVideo(const std::string& path);

/// A frame-number pattern: exactly one %d or %0Nd (N from 1 to 9) and no other '%'. Parsed here:
/// a path is never handed to printf as a format.
struct SequencePattern {
  std::string prefix, suffix;
  int width = 0;  ///< zero-padded to this many digits (0: no padding)
  std::string at(int i) const;
};
/// The pattern in `spec`, or none when it has no valid one.
std::optional<SequencePattern> parseSequencePattern(const std::string& spec);

}  // namespace lp
