#pragma once
namespace lp::gl::shaders {
extern const char* const kModelVs;
extern const char* const kModelFs;
extern const char* const kBackgroundVs;
extern const char* const kBackgroundFs;
extern const char* const kProbeFs;
}  // namespace lp::gl::shaders
