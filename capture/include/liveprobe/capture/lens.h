#pragma once
// A real camera's lens, as the ecosystem writes its calibration: OpenCV's FileStorage YAML or
// JSON (camera_matrix, distortion_coefficients, image_width, image_height, distortion_model:
// `fisheye` for the Kannala-Brandt model of cv::fisheye, `plumb_bob` or `rational_polynomial`
// for cv::calibrateCamera's), or ROS's camera_info YAML (distortion_model `equidistant`, the same
// Kannala-Brandt model, or `plumb_bob`). The convention: a direction in OpenCV's camera frame
// (x right, y down, z along the optical axis) is the same vector in liveprobe's world frame
// (liveprobe/sh/sh.h: z up), so a camera looking straight up needs no rotation.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "liveprobe/sh/layout.h"

namespace lp {

struct LensCalibration {
  enum class Model {
    Fisheye,  ///< Kannala-Brandt, theta_d = theta (1 + k1 t^2 + k2 t^4 + k3 t^6 + k4 t^8): 4 k
    Pinhole,  ///< Brown-Conrady (plumb_bob: 5 coefficients; rational_polynomial: 8, up to 14)
  };
  Model model = Model::Fisheye;
  int width = 0, height = 0;       ///< the image size the calibration was made at
  std::array<double, 9> K{};       ///< the camera matrix, row-major (fx 0 cx; 0 fy cy; 0 0 1)
  std::vector<double> distortion;  ///< as the model orders them
  std::string source;              ///< the file it came from (for messages)
};

/// Reads a lens calibration (OpenCV FileStorage .yaml/.yml/.json, or ROS camera_info .yaml).
/// Throws lp::Error naming `path` and the fault in one line: a missing key, a matrix that is not
/// 3x3 with fx, fy > 0 and a last row 0 0 1, a value that is not finite, a distortion of the
/// wrong length for its model, an unknown model, a size that is not positive.
LensCalibration readLensCalibration(const std::string& path);

/// The lens as the projection sees it (liveprobe/sh/layout.h's LensModel), with OpenCV doing the
/// lens model: each pixel's direction is its centre undistorted (cv::fisheye::undistortPoints, or
/// cv::undistortPoints iterated to convergence) and checked by distorting it back; each pixel's
/// solid angle is the spherical quadrilateral of its four corners' directions. Pixels whose
/// direction the model cannot give (90 degrees or more from the axis, beyond where the
/// distortion turns back, or off the frame) are unseen. A frame of the calibration's aspect but
/// another size is the same lens scaled; another aspect is refused.
std::shared_ptr<const LensModel> makeLensModel(const LensCalibration& calibration);

/// A mirror ball filmed through the calibrated `camera`, its silhouette the circle (centre x,
/// centre y, radius, in pixels of the frame, centres at +0.5), traced as it is rather than from
/// infinitely far: each pixel's ray meets the ball at the distance the circle's angular size
/// implies and reflects. The world is the mirror-ball layout's (liveprobe/sh/layout.h): the ray to
/// the ball's centre is +x, the camera's right -y, its up +z, so a ball far away gives the
/// orthographic mirror ball's directions. Unseen (filled by LayoutSpec::unseen): the cone behind
/// the ball (within its angular radius alpha of +x) and the camera's own reflection (within alpha
/// of -x). Each pixel's solid angle is the spherical quadrilateral of its corners' reflections.
std::shared_ptr<const LensModel> makeBallModel(const LensCalibration& camera, glm::vec3 circle);

/// The radius, in pixels of a W x H frame (of the calibration's aspect), of the disc about the
/// principal point within which the lens sees every pixel (a fisheye's image circle, black beyond
/// it); 0 where it sees the whole frame.
double seenRadius(const LensCalibration& calibration, int width, int height);

}  // namespace lp
