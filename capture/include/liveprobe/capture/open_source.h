#pragma once
// The frame sources liveprobe::capture opens by name, and the synthetic sky.
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <vector>

#include "liveprobe/frame/frame.h"

namespace lp {

struct SourceOptions {
  double fps = 30.0;      ///< for image sequences and stills, which carry no timing
  int timeoutMs = 10000;  ///< a URL: connecting, and the longest wait for a frame
};

/// Opens SOURCE:
///   synthetic[:WxH[@FPS]]       the procedural sky (default 512x256 at 30 fps)
///   DIR with px,nx,py,ny,pz,nz  six cube faces, assembled into a horizontal cross
///   DIR                         an image sequence (image files in name order)
///   PATTERN with %d or %0Nd     an image sequence by frame number (frame_%04d.png; the one
///                               pattern is parsed here, never used as a printf format)
///   *.mp4|webm|mkv|avi|mov|m4v  a video file, decoded by FFmpeg through OpenCV
///   rtsp|http(s)|srt|udp|...:// a stream or a file on a server, read frame by frame through
///                               FFmpeg (liveprobe/capture/network.h)
///   anything else               a still image
/// Throws lp::Error naming the source on failure.
std::unique_ptr<FrameSource> openSource(const std::string& spec, const SourceOptions& options = {});

/// The synthetic sky at time t (seconds): an equirect HDR with a moving sun, a sky gradient, a
/// ground, and two coloured area lights moving around the horizon. Deterministic in t.
void renderSyntheticSky(int width, int height, double t, std::vector<float>& rgb);
/// Where the synthetic sky's sun is at time t: a full turn of azimuth every 20 s, elevation
/// 30 + 20 sin(2 pi t / 10) degrees (unit, R&H frame). The truth that light tracking is tested on.
glm::vec3 syntheticSunDirection(double t);

}  // namespace lp
