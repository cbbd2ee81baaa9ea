#pragma once
// A lens calibrated from photos of a chessboard, with OpenCV's detector and calibration, written
// as OpenCV's FileStorage YAML that `--lens` (liveprobe/capture/lens.h) and cv::FileStorage read.
#include <string>
#include <utility>
#include <vector>

#include "liveprobe/capture/lens.h"

namespace lp {

/// A chessboard: its inner corners (columns x rows, as cv::findChessboardCorners counts them) and
/// the side of a square (any unit: the calibration's focal lengths and centre are in pixels
/// whatever it is).
struct Chessboard {
  int cols = 0, rows = 0;
  double square = 1.0;
};

/// What a calibration found, and how far it can be trusted.
struct LensFit {
  LensCalibration lens;
  double rms = 0;  ///< RMS reprojection error over every corner, pixels
  std::vector<std::string> used;
  std::vector<std::pair<std::string, std::string>> refused;  ///< a photo, and why
  /// The field divided in 3 x 3: how many parts hold a corner, and those that hold none
  /// ("top left", ...).
  int partsCovered = 0;
  std::vector<std::string> partsMissed;
};

/// The fewest photos showing the board that a calibration takes.
inline constexpr int kMinCalibrationBoards = 3;

/// Calibrates the lens of the photos at `paths` (one camera, one size) from the board they show:
/// the corners found by cv::findChessboardCornersSB, the model fitted by cv::fisheye::calibrate
/// (Kannala-Brandt) or cv::calibrateCamera (Brown-Conrady, 5 coefficients). A wide fisheye is not
/// fitted from no guess (cv::fisheye::calibrate diverges on boards far off the axis): it starts
/// at the image's centre with focal lengths from a 180-degree lens filling the frame's shorter
/// side, and from a few others around it, each refined by OpenCV (which places the boards from
/// their homographies under the guess); the lowest RMS wins. Throws lp::Error in one line: a
/// photo that cannot be read or is of another size, or fewer than kMinCalibrationBoards photos
/// showing the board (saying how many did and why the others were refused).
LensFit calibrateLens(const std::vector<std::string>& paths, const Chessboard& board,
                      LensCalibration::Model model);

/// Writes `fit` as OpenCV's FileStorage YAML (image_width, image_height, camera_matrix,
/// distortion_coefficients, distortion_model, and the fit's rms and photos), atomically.
void writeLensCalibration(const std::string& path, const LensFit& fit);

}  // namespace lp
