#pragma once
// A lens calibrated from photos of a chessboard, with OpenCV's detector and calibration, written
// as OpenCV's FileStorage YAML that `--lens` (liveprobe/capture/lens.h) and cv::FileStorage read.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "liveprobe/capture/lens.h"
#include "liveprobe/frame/frame.h"

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

/// A board seen in one photo or frame: its inner corners in OpenCV's pixel coordinates (centres
/// at whole numbers), in the detector's order.
struct BoardView {
  std::string name;
  std::vector<std::array<float, 2>> corners;
};

/// The board in an 8-bit grey image (rows `stride` bytes apart), its corners found by
/// cv::findChessboardCornersSB and refined where they are by cv::cornerSubPix; none when the
/// board is not there. `quick` skips the exhaustive search and the refinement (a live frame
/// checked for a board that is held still).
std::optional<std::vector<std::array<float, 2>>> findBoard(const std::uint8_t* grey, int width,
                                                           int height, std::size_t stride,
                                                           const Chessboard& board, bool quick);

/// The lens fitted to boards already found in W x H images (`refused`: the images that showed
/// none, and why, carried into the result). Throws lp::Error as calibrateLens.
LensFit fitLens(const std::vector<BoardView>& views, int width, int height, const Chessboard& board,
                LensCalibration::Model model,
                std::vector<std::pair<std::string, std::string>> refused = {});

/// Boards kept from a live camera's frames: a frame's board is kept when it is held still (its
/// corners within half a pixel of the last frame's) in a new place (its corners a twentieth of
/// the frame's shorter side or more from every kept board's, on average).
class BoardCollector {
 public:
  BoardCollector(const Chessboard& board) : board_(board) {}
  enum class Seen { NoBoard, Moving, AlreadyKept, Kept };
  /// Looks for the board in `frame` (8-bit or float).
  Seen offer(const Frame& frame);
  const std::vector<BoardView>& views() const { return views_; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  Chessboard board_;
  int width_ = 0, height_ = 0;
  std::optional<std::vector<std::array<float, 2>>> last_;
  std::vector<BoardView> views_;
};

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
