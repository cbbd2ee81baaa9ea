#pragma once
namespace lp::gl::shaders {
extern const char* const kModelVs;
extern const char* const kModelFs;
extern const char* const kBackgroundVs;
extern const char* const kBackgroundFs;
extern const char* const kProbeFs;
extern const char* const kDepthVs;
extern const char* const kDepthFs;
extern const char* const kGroundVs;
extern const char* const kGroundFs;
}  // namespace lp::gl::shaders
