#pragma once
// A camera's response recovered from frames of one still scene at several exposure times.
#include <vector>

#include "liveprobe/frame/frame.h"
#include "liveprobe/hdr/response.h"

namespace lp {

/// The darkest code an 8-bit frame reads over a part of its scene (0.05% of its samples or more,
/// any channel): a calibration sweep goes shorter until this is kDarkestCode.
int darkestCode(const Frame& frame);

/// A camera's response recovered from 8-bit frames of one static scene, each with its own
/// exposure time (Frame::radianceScale = 1 / exposure): the least squares of the codes each pixel
/// took in each pair of frames (comparametric equations), with a smoothness over log(code) that
/// any power law passes freely; normalised so that green's power law over codes 32-240 reaches 1
/// at code 255; readFrom..readTo the codes every channel read. Throws lp::Error with fewer than 3
/// distinct exposures, with too few codes read, or when the recovered curve falls somewhere (too
/// few tones in the scene, or a scene that moved).
///
/// A camera that sends a colour shared by a block of pixels (YUYV: 2x1, NV12 and most MJPEG:
/// 2x2) gives a pixel's code in each channel only where its block reads one colour: only those
/// pixels are read, and not within 3 codes of 0 or 255 (where the YUV steps make a clipped
/// channel read as unclipped). The YUV's own 8-bit steps remain: such a curve holds within 3%
/// from kYuvTrustedFrom up (HdrMerge.TheResponseRecoveryAgainstOpenCvs).
struct ChromaBlock {
  int width = 1, height = 1;
};
inline constexpr int kYuvTrustedFrom = 16;
CameraResponse calibrateResponse(const std::vector<Frame>& frames, ChromaBlock chroma = {});

}  // namespace lp
