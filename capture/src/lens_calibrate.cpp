#include "liveprobe/capture/lens_calibrate.h"

#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "liveprobe/capture/atomic_file.h"
#include "liveprobe/frame/input_file.h"
#include "liveprobe/sh/error.h"

namespace lp {

namespace {

/// The board's corners in its own plane, row by row as the detector orders them.
std::vector<cv::Point3f> boardPoints(const Chessboard& b) {
  std::vector<cv::Point3f> pts;
  for (int r = 0; r < b.rows; ++r)
    for (int c = 0; c < b.cols; ++c)
      pts.emplace_back(float(c * b.square), float(r * b.square), 0.0f);
  return pts;
}

/// The Kannala-Brandt fit from one starting focal length; NaN RMS where OpenCV gives up.
double fitFisheye(const std::vector<std::vector<cv::Point3d>>& object,
                  const std::vector<std::vector<cv::Point2d>>& image, cv::Size size, double focal,
                  cv::Matx33d& K, cv::Vec4d& D) {
  K = cv::Matx33d(focal, 0, (size.width - 1) / 2.0, 0, focal, (size.height - 1) / 2.0, 0, 0, 1);
  D = cv::Vec4d(0, 0, 0, 0);
  std::vector<cv::Vec3d> rvecs, tvecs;
  try {
    return cv::fisheye::calibrate(
        object, image, size, K, D, rvecs, tvecs,
        cv::fisheye::CALIB_USE_INTRINSIC_GUESS | cv::fisheye::CALIB_RECOMPUTE_EXTRINSIC |
            cv::fisheye::CALIB_FIX_SKEW,
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-12));
  } catch (const cv::Exception&) {
    return std::numeric_limits<double>::quiet_NaN();
  }
}

/// The RMS reprojection error of a fisheye fit, over every corner (cv::fisheye::calibrate's own
/// figure is of the last iteration's residual, in a different normalisation).
double fisheyeRms(const std::vector<std::vector<cv::Point3d>>& object,
                  const std::vector<std::vector<cv::Point2d>>& image, const cv::Matx33d& K,
                  const cv::Vec4d& D) {
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < object.size(); ++i) {
    cv::Vec3d rvec, tvec;
    // The board's pose under the fitted lens: undistort its corners, then solve the plane.
    std::vector<cv::Point2d> flat;
    cv::fisheye::undistortPoints(image[i], flat, K, D);
    if (!cv::solvePnP(object[i], flat, cv::Matx33d::eye(), cv::noArray(), rvec, tvec))
      return std::numeric_limits<double>::infinity();
    std::vector<cv::Point2d> back;
    cv::fisheye::projectPoints(object[i], back, rvec, tvec, K, D);
    for (std::size_t k = 0; k < back.size(); ++k) {
      const cv::Point2d d = back[k] - image[i][k];
      sum += d.dot(d);
      ++n;
    }
  }
  return n ? std::sqrt(sum / double(n)) : std::numeric_limits<double>::infinity();
}

void checkBoard(const Chessboard& board) {
  if (board.cols < 2 || board.rows < 2 || !(board.square > 0))
    throw Error("the board needs at least 2x2 inner corners and a square of positive size");
}

void checkFit(const cv::Matx33d& K, const std::vector<double>& D, cv::Size size) {
  bool ok = K(0, 0) > 0 && K(1, 1) > 0 && K(0, 2) > 0 && K(1, 2) > 0 && K(0, 2) < size.width &&
            K(1, 2) < size.height;
  for (const double d : D) ok = ok && std::isfinite(d);
  if (!ok) throw Error("the calibration did not converge (a centre off the frame)");
}

}  // namespace

std::optional<std::vector<std::array<float, 2>>> findBoard(const std::uint8_t* grey, int width,
                                                           int height, std::size_t stride,
                                                           const Chessboard& board, bool quick) {
  const cv::Mat image(height, width, CV_8UC1, const_cast<std::uint8_t*>(grey), stride);
  std::vector<cv::Point2f> found;
  if (!cv::findChessboardCornersSB(image, cv::Size(board.cols, board.rows), found,
                                   quick ? 0 : cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY))
    return std::nullopt;
  // Each corner refined where it is: the sector detector's fit assumes straight lines across
  // the board, which a fisheye bends.
  if (!quick)
    cv::cornerSubPix(image, found, cv::Size(4, 4), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 50, 1e-4));
  std::vector<std::array<float, 2>> out;
  out.reserve(found.size());
  for (const cv::Point2f& p : found) out.push_back({p.x, p.y});
  return out;
}

LensFit calibrateLens(const std::vector<std::string>& paths, const Chessboard& board,
                      LensCalibration::Model model) {
  checkBoard(board);
  cv::Size size;
  std::vector<BoardView> views;
  std::vector<std::pair<std::string, std::string>> refused;
  for (const std::string& path : paths) {
    requireRegularFile(path);
    const cv::Mat gray = cv::imread(path, cv::IMREAD_GRAYSCALE);
    if (gray.empty()) throw Error(path + ": not an image OpenCV reads");
    if (size.area() == 0) size = gray.size();
    if (gray.size() != size)
      throw Error(path + ": " + std::to_string(gray.cols) + "x" + std::to_string(gray.rows) +
                  ", the first photo is " + std::to_string(size.width) + "x" +
                  std::to_string(size.height) + " (one camera, one size)");
    if (auto corners = findBoard(gray.data, gray.cols, gray.rows, gray.step, board, false))
      views.push_back({path, std::move(*corners)});
    else
      refused.emplace_back(path, "no " + std::to_string(board.cols) + "x" +
                                     std::to_string(board.rows) + " board found");
  }
  return fitLens(views, size.width, size.height, board, model, std::move(refused));
}

LensFit fitLens(const std::vector<BoardView>& views, int width, int height, const Chessboard& board,
                LensCalibration::Model model,
                std::vector<std::pair<std::string, std::string>> refused) {
  checkBoard(board);
  LensFit fit;
  fit.refused = std::move(refused);
  const cv::Size size(width, height);
  const std::vector<cv::Point3f> corners3 = boardPoints(board);
  std::vector<std::vector<cv::Point3d>> object;
  std::vector<std::vector<cv::Point2d>> image;
  std::vector<cv::Point2f> all;
  for (const BoardView& v : views) {
    if (v.corners.size() != corners3.size()) continue;
    fit.used.push_back(v.name);
    object.emplace_back(corners3.begin(), corners3.end());
    image.emplace_back();
    for (const auto& c : v.corners) {
      image.back().emplace_back(c[0], c[1]);
      all.emplace_back(c[0], c[1]);
    }
  }
  if (int(fit.used.size()) < kMinCalibrationBoards) {
    std::string why = std::to_string(fit.used.size()) + " of " +
                      std::to_string(views.size() + fit.refused.size()) + " photos show the " +
                      std::to_string(board.cols) + "x" + std::to_string(board.rows) +
                      " board; a calibration needs at least " +
                      std::to_string(kMinCalibrationBoards);
    for (const auto& [p, r] : fit.refused) why += "; " + p + ": " + r;
    throw Error(why);
  }

  LensCalibration& lens = fit.lens;
  lens.model = model;
  lens.width = size.width, lens.height = size.height;
  cv::Matx33d K;
  if (model == LensCalibration::Model::Fisheye) {
    // Starting focal lengths: a 180-degree equidistant lens whose circle fills the shorter side,
    // and half to twice that; the one whose fit reprojects best wins.
    const double f180 = std::min(size.width, size.height) / kPi;
    double best = std::numeric_limits<double>::infinity();
    cv::Vec4d bestD;
    for (const double scale : {1.0, 0.5, 0.7, 1.4, 2.0}) {
      cv::Matx33d k;
      cv::Vec4d d;
      if (!std::isfinite(fitFisheye(object, image, size, f180 * scale, k, d))) continue;
      const double rms = fisheyeRms(object, image, k, d);
      if (rms < best) best = rms, K = k, bestD = d;
    }
    if (!std::isfinite(best))
      throw Error("the fisheye calibration did not converge from any starting focal length");
    fit.rms = best;
    lens.distortion.assign(bestD.val, bestD.val + 4);
  } else {
    std::vector<double> D;
    std::vector<cv::Mat> rvecs, tvecs;
    std::vector<std::vector<cv::Point3f>> obj(object.size(), corners3);
    std::vector<std::vector<cv::Point2f>> img;
    for (const auto& v : image) img.emplace_back(v.begin(), v.end());
    fit.rms = cv::calibrateCamera(obj, img, size, K, D, rvecs, tvecs);
    lens.distortion = D;
  }
  checkFit(K, lens.distortion, size);
  for (int i = 0; i < 9; ++i) lens.K[std::size_t(i)] = K.val[i];

  // Which ninths of the field the corners reached.
  static const char* const kParts[9] = {"top left",    "top",    "top right",
                                        "left",        "centre", "right",
                                        "bottom left", "bottom", "bottom right"};
  bool hit[9] = {};
  for (const cv::Point2f& p : all)
    hit[std::clamp(int(3 * p.y / size.height), 0, 2) * 3 +
        std::clamp(int(3 * p.x / size.width), 0, 2)] = true;
  for (int i = 0; i < 9; ++i) {
    if (hit[i])
      ++fit.partsCovered;
    else
      fit.partsMissed.emplace_back(kParts[i]);
  }
  return fit;
}

namespace {

/// Mean distance between two boards' corners, either way round (the detector may start a
/// board from the opposite corner).
double boardDistance(const std::vector<std::array<float, 2>>& a,
                     const std::vector<std::array<float, 2>>& b) {
  if (a.size() != b.size() || a.empty()) return HUGE_VAL;
  double same = 0, reversed = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const auto& r = b[b.size() - 1 - i];
    same += std::hypot(a[i][0] - b[i][0], a[i][1] - b[i][1]);
    reversed += std::hypot(a[i][0] - r[0], a[i][1] - r[1]);
  }
  return std::min(same, reversed) / double(a.size());
}

}  // namespace

BoardCollector::Seen BoardCollector::offer(const Frame& frame) {
  if (width_ == 0) width_ = frame.width, height_ = frame.height;
  if (frame.width != width_ || frame.height != height_)
    throw Error("the camera's frames changed size to " + std::to_string(frame.width) + "x" +
                std::to_string(frame.height) + " from " + std::to_string(width_) + "x" +
                std::to_string(height_));
  cv::Mat grey;
  if (frame.format == PanoramaFormat::BgrU8) {
    cv::cvtColor(
        cv::Mat(frame.height, frame.width, CV_8UC3, const_cast<std::uint8_t*>(frame.bgr8.data())),
        grey, cv::COLOR_BGR2GRAY);
  } else {
    cv::Mat rgb(frame.height, frame.width, CV_32FC3, const_cast<float*>(frame.rgb.data())), y;
    cv::cvtColor(rgb, y, cv::COLOR_RGB2GRAY);
    y.convertTo(grey, CV_8U, 255);
  }
  auto quick = findBoard(grey.data, grey.cols, grey.rows, grey.step, board_, true);
  const bool still = quick && last_ && boardDistance(*quick, *last_) < 0.5;
  last_ = std::move(quick);
  if (!last_) return Seen::NoBoard;
  if (!still) return Seen::Moving;
  const double apart = 0.05 * std::min(width_, height_);
  for (const BoardView& v : views_)
    if (boardDistance(*last_, v.corners) < apart) return Seen::AlreadyKept;
  auto corners = findBoard(grey.data, grey.cols, grey.rows, grey.step, board_, false);
  if (!corners) return Seen::Moving;
  views_.push_back({"frame " + std::to_string(frame.sequence), std::move(*corners)});
  return Seen::Kept;
}

void writeLensCalibration(const std::string& path, const LensFit& fit) {
  AtomicOutput out(path);
  const LensCalibration& l = fit.lens;
  try {
    cv::FileStorage fs(out.temporary(), cv::FileStorage::WRITE);
    if (!fs.isOpened()) throw Error(path + ": cannot write (OpenCV FileStorage)");
    fs << "image_width" << l.width << "image_height" << l.height;
    fs << "camera_matrix" << cv::Mat(cv::Matx33d(l.K.data()));
    fs << "distortion_coefficients" << cv::Mat(l.distortion).t();
    fs << "distortion_model"
       << (l.model == LensCalibration::Model::Fisheye ? "fisheye" : "plumb_bob");
    fs << "rms_reprojection_error" << fit.rms;
    fs << "photos_used" << int(fit.used.size());
    fs.release();
  } catch (const cv::Exception& e) {
    throw Error(path + ": cannot write (" + e.err + ")");
  }
  out.commit();
}

}  // namespace lp
