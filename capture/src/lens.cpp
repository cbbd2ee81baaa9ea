#include "liveprobe/capture/lens.h"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/core/utility.hpp>

#include "liveprobe/frame/input_file.h"
#include "liveprobe/sh/error.h"

namespace lp {

namespace {

/// A matrix node's numbers: OpenCV's `!!opencv-matrix` and ROS's plain map both keep them under
/// `data` with `rows` and `cols`; a bare sequence is taken as it is.
std::vector<double> numbers(const cv::FileNode& node, const std::string& where,
                            const std::string& name, int& rows, int& cols) {
  if (node.empty() || node.isNone()) throw Error(where + ": no " + name);
  const cv::FileNode data = node.isMap() ? node["data"] : node;
  if (!data.isSeq()) throw Error(where + ": " + name + " has no data sequence");
  rows = node.isMap() && node["rows"].isInt() ? int(node["rows"]) : 1;
  cols = node.isMap() && node["cols"].isInt() ? int(node["cols"]) : int(data.size());
  std::vector<double> v;
  for (const cv::FileNode& n : data) {
    if (!n.isReal() && !n.isInt())
      throw Error(where + ": " + name + " holds a value that is not a number");
    const double x = double(n);
    if (!std::isfinite(x)) throw Error(where + ": " + name + " holds a value that is not finite");
    v.push_back(x);
  }
  if (rows < 1 || cols < 1 || std::size_t(rows) * std::size_t(cols) != v.size())
    throw Error(where + ": " + name + " says " + std::to_string(rows) + "x" + std::to_string(cols) +
                " but holds " + std::to_string(v.size()) + " numbers");
  return v;
}

int positive(const cv::FileNode& node, const std::string& where, const std::string& name) {
  if (node.empty() || node.isNone()) throw Error(where + ": no " + name);
  if (!node.isInt() || int(node) < 1 || int(node) > 65536)
    throw Error(where + ": " + name + " must be a whole number of pixels from 1 to 65536");
  return int(node);
}

}  // namespace

LensCalibration readLensCalibration(const std::string& path) {
  // ROS's camera_info YAML has no %YAML directive, which OpenCV's parser requires: the text is
  // given one where it lacks it (JSON and OpenCV's own YAML are read as they are).
  std::string text = readInputFile(path);
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) throw Error(path + ": not a lens calibration (empty)");
  if (text[first] != '{' && text[first] != '<') {
    if (text.compare(first, 6, "%YAML:") != 0) {
      if (text.compare(first, 5, "%YAML") == 0) text.erase(0, text.find('\n', first));
      text.insert(0, "%YAML:1.0\n---\n");
    }
  }
  cv::FileStorage fs;
  try {
    if (!fs.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY))
      throw Error(path + ": not a lens calibration (OpenCV cannot read it as YAML or JSON)");
  } catch (const cv::Exception& e) {
    throw Error(path + ": not a lens calibration (" + e.err + ")");
  }
  LensCalibration lens;
  lens.source = path;
  try {
    const cv::FileNode root = fs.root();
    lens.width = positive(root["image_width"], path, "image_width");
    lens.height = positive(root["image_height"], path, "image_height");
    int rows = 0, cols = 0;
    const std::vector<double> k = numbers(root["camera_matrix"], path, "camera_matrix", rows, cols);
    if (rows != 3 || cols != 3) throw Error(path + ": camera_matrix must be 3x3");
    std::copy(k.begin(), k.end(), lens.K.begin());
    if (!(lens.K[0] > 0) || !(lens.K[4] > 0))
      throw Error(path + ": camera_matrix has no positive focal length (fx, fy)");
    if (lens.K[3] != 0 || lens.K[6] != 0 || lens.K[7] != 0 || lens.K[8] != 1)
      throw Error(path + ": camera_matrix's last row must be 0 0 1 and its second start with 0");
    lens.distortion =
        numbers(root["distortion_coefficients"], path, "distortion_coefficients", rows, cols);
    const cv::FileNode modelNode = root["distortion_model"];
    if (modelNode.empty() || !modelNode.isString())
      throw Error(path +
                  ": no distortion_model (fisheye or equidistant, plumb_bob, "
                  "rational_polynomial)");
    const std::string model = std::string(modelNode);
    const std::size_t n = lens.distortion.size();
    if (model == "fisheye" || model == "equidistant") {
      lens.model = LensCalibration::Model::Fisheye;
      if (n != 4)
        throw Error(path + ": a " + model + " lens has 4 distortion coefficients, not " +
                    std::to_string(n));
    } else if (model == "plumb_bob" || model == "rational_polynomial") {
      lens.model = LensCalibration::Model::Pinhole;
      if (n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
        throw Error(path + ": a " + model +
                    " lens has 4, 5, 8, 12 or 14 distortion coefficients, " + "not " +
                    std::to_string(n));
    } else {
      throw Error(path + ": distortion_model " + model +
                  " is not one liveprobe reads (fisheye or equidistant, plumb_bob, "
                  "rational_polynomial)");
    }
  } catch (const cv::Exception& e) {
    throw Error(path + ": not a lens calibration (" + e.err + ")");
  }
  return lens;
}

namespace {

/// A calibration as a LensModel. Points go through OpenCV in normalised coordinates (the camera
/// matrix applied here, skew included, with OpenCV's pixel centres at whole numbers), so both
/// models see the same K.
class OpenCvLens final : public LensModel {
 public:
  explicit OpenCvLens(LensCalibration c) : c_(std::move(c)), d_(c_.distortion) {}

  std::string mismatch(int width, int height) const override {
    if (std::int64_t(width) * c_.height == std::int64_t(height) * c_.width) return {};
    return c_.source + " was calibrated at " + std::to_string(c_.width) + "x" +
           std::to_string(c_.height) + ", this frame is " + std::to_string(width) + "x" +
           std::to_string(height) + " (another aspect)";
  }

  std::string scaling(int width, int height) const override {
    if (width == c_.width && height == c_.height) return {};
    return "the lens calibrated at " + std::to_string(c_.width) + "x" + std::to_string(c_.height) +
           " (" + c_.source + ") scaled to this " + std::to_string(width) + "x" +
           std::to_string(height) + " frame";
  }

  std::string describe() const override {
    return std::string(c_.model == LensCalibration::Model::Fisheye ? "fisheye" : "pinhole") +
           " lens " + c_.source;
  }

  std::vector<SphereSample> samples(int width, int height) const override {
    const Intrinsics k = at(width);
    const std::size_t w = std::size_t(width), h = std::size_t(height);
    // Corner (x, y) of the grid is the top-left corner of pixel (x, y); liveprobe's pixel
    // coordinates put centres at +0.5, so the corner is at x, y there.
    std::vector<glm::dvec3> corners((w + 1) * (h + 1));
    std::vector<SphereSample> out(w * h);
    cv::parallel_for_(cv::Range(0, height + 1), [&](const cv::Range& rows) {
      std::vector<cv::Point2d> pts;
      std::vector<glm::dvec3> dirs;
      for (int y = rows.start; y < rows.end; ++y) {
        pts.clear();
        for (std::size_t x = 0; x <= w; ++x) pts.push_back(k.normalise(double(x), double(y)));
        directions(pts, k, dirs);
        std::copy(dirs.begin(), dirs.end(),
                  corners.begin() + std::ptrdiff_t(std::size_t(y) * (w + 1)));
      }
    });
    cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
      std::vector<cv::Point2d> pts;
      std::vector<glm::dvec3> dirs;
      for (int y = rows.start; y < rows.end; ++y) {
        pts.clear();
        for (std::size_t x = 0; x < w; ++x) pts.push_back(k.normalise(x + 0.5, y + 0.5));
        directions(pts, k, dirs);
        for (std::size_t x = 0; x < w; ++x) {
          const glm::dvec3* c = &corners[std::size_t(y) * (w + 1) + x];
          const glm::dvec3 a = c[0], b = c[1], d = c[w + 1], e = c[w + 2];
          SphereSample& s = out[std::size_t(y) * w + x];
          if (!valid(dirs[x]) || !valid(a) || !valid(b) || !valid(d) || !valid(e)) {
            s = {glm::vec3(0, 0, 1), 0.0f};
            continue;
          }
          // The corners in order round the pixel: a b (top), e d (bottom).
          s = {glm::vec3(dirs[x]), float(triangle(a, b, e) + triangle(a, e, d))};
        }
      }
    });
    return out;
  }

  void pixels(int width, int height, const glm::vec3* dirs, std::size_t count,
              glm::vec2* out) const override {
    const Intrinsics k = at(width);
    std::vector<cv::Point3d> ahead;
    std::vector<std::size_t> which;
    for (std::size_t i = 0; i < count; ++i) {
      out[i] = glm::vec2(NAN);
      const glm::dvec3 d(dirs[i]);
      if (d.z > 1e-9 * glm::length(d))
        ahead.emplace_back(d.x / d.z, d.y / d.z, 1.0), which.push_back(i);
    }
    if (ahead.empty()) return;
    std::vector<cv::Point2d> distorted = distort(ahead);
    // Back again: a direction beyond where the distortion turns back lands on a pixel that
    // looks elsewhere.
    std::vector<glm::dvec3> back;
    directions(distorted, k, back);
    for (std::size_t n = 0; n < which.size(); ++n) {
      const glm::dvec3 d = glm::normalize(glm::dvec3(ahead[n].x, ahead[n].y, 1.0));
      if (!valid(back[n]) || glm::dot(d, back[n]) < std::cos(1e-4)) continue;
      const glm::dvec2 px = k.pixel(distorted[n]);
      if (px.x >= 0 && px.y >= 0 && px.x < width && px.y < height) out[which[n]] = glm::vec2(px);
    }
  }

 private:
  /// The camera matrix for a W x H frame (the calibration's, scaled).
  struct Intrinsics {
    double fx, fy, cx, cy, skew;
    double tolerance;  ///< normalised distance a hundredth of a pixel spans
    /// liveprobe pixel coordinates -> normalised (distorted) image coordinates.
    cv::Point2d normalise(double x, double y) const {
      const double v = (y - 0.5 - cy) / fy;
      return {(x - 0.5 - cx - skew * v) / fx, v};
    }
    glm::dvec2 pixel(cv::Point2d n) const {
      return {fx * n.x + skew * n.y + cx + 0.5, fy * n.y + cy + 0.5};
    }
  };
  Intrinsics at(int width) const {
    const double s = double(width) / c_.width;
    // OpenCV's pixel centres are whole numbers: scale about the image's corner, (-0.5, -0.5).
    const double fx = c_.K[0] * s, fy = c_.K[4] * s;
    return {fx,
            fy,
            (c_.K[2] + 0.5) * s - 0.5,
            (c_.K[5] + 0.5) * s - 0.5,
            c_.K[1] * s,
            0.01 / std::max(fx, fy)};
  }

  static bool valid(const glm::dvec3& d) { return d.z > 0; }

  /// Undistorted points on the plane z = 1 -> distorted normalised image points.
  std::vector<cv::Point2d> distort(const std::vector<cv::Point3d>& ahead) const {
    std::vector<cv::Point2d> out;
    const cv::Matx33d eye = cv::Matx33d::eye();
    if (c_.model == LensCalibration::Model::Fisheye) {
      std::vector<cv::Point2d> flat(ahead.size());
      for (std::size_t i = 0; i < ahead.size(); ++i) flat[i] = {ahead[i].x, ahead[i].y};
      cv::fisheye::distortPoints(flat, out, eye, d_);
    } else {
      cv::projectPoints(ahead, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), eye, d_, out);
    }
    return out;
  }

  /// The Kannala-Brandt model inverted: theta from theta_d = theta (1 + k1 t^2 + ... + k4 t^8)
  /// by Newton's method, to the plane z = 1 (infinite at 90 degrees and beyond: NaN there).
  /// cv::fisheye::undistortPoints clamps theta_d at pi/2 (OpenCV 4.6), which loses the rim of a
  /// lens that sees 180 degrees; every point is checked by distorting it back through OpenCV.
  std::vector<cv::Point2d> undistortFisheye(const std::vector<cv::Point2d>& pts) const {
    const double* k = d_.data();
    const auto thetaD = [&](double t) {
      const double t2 = t * t;
      return t * (1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
    };
    const auto slope = [&](double t) {
      const double t2 = t * t;
      return 1 + t2 * (3 * k[0] + t2 * (5 * k[1] + t2 * (7 * k[2] + t2 * 9 * k[3])));
    };
    std::vector<cv::Point2d> out(pts.size(), cv::Point2d(NAN, NAN));
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double rd = std::hypot(pts[i].x, pts[i].y);
      if (rd < 1e-15) {
        out[i] = {0.0, 0.0};
        continue;
      }
      double t = rd;
      for (int n = 0; n < 30; ++n) {
        const double s = slope(t);
        if (!(s > 0)) break;
        const double step = (thetaD(t) - rd) / s;
        t -= step;
        if (std::abs(step) < 1e-15) break;
      }
      if (!(t >= 0 && t < kHalfPi)) continue;
      const double scale = std::tan(t) / rd;
      out[i] = {pts[i].x * scale, pts[i].y * scale};
    }
    return out;
  }
  static constexpr double kHalfPi = 1.57079632679489661923;

  /// Distorted normalised image points -> unit directions, (0, 0, 0) where the model gives none
  /// (the undistortion does not distort back to the point).
  void directions(const std::vector<cv::Point2d>& pts, const Intrinsics& k,
                  std::vector<glm::dvec3>& out) const {
    std::vector<cv::Point2d> flat;
    const cv::Matx33d eye = cv::Matx33d::eye();
    const cv::TermCriteria until(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-14);
    if (c_.model == LensCalibration::Model::Fisheye)
      flat = undistortFisheye(pts);
    else
      cv::undistortPoints(pts, flat, eye, d_, cv::noArray(), cv::noArray(), until);
    std::vector<cv::Point3d> ahead(flat.size());
    for (std::size_t i = 0; i < flat.size(); ++i) ahead[i] = {flat[i].x, flat[i].y, 1.0};
    const std::vector<cv::Point2d> again = distort(ahead);
    out.assign(pts.size(), glm::dvec3(0.0));
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (!std::isfinite(flat[i].x) || !std::isfinite(flat[i].y)) continue;
      if (std::hypot(again[i].x - pts[i].x, again[i].y - pts[i].y) > k.tolerance) continue;
      out[i] = glm::normalize(glm::dvec3(flat[i].x, flat[i].y, 1.0));
    }
  }

  /// The solid angle of the spherical triangle a b c (Van Oosterom and Strackee).
  static double triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const double num = std::abs(glm::dot(a, glm::cross(b, c)));
    const double den = 1.0 + glm::dot(a, b) + glm::dot(b, c) + glm::dot(c, a);
    return 2.0 * std::atan2(num, den);
  }

  LensCalibration c_;
  std::vector<double> d_;
};

}  // namespace

std::shared_ptr<const LensModel> makeLensModel(const LensCalibration& calibration) {
  return std::make_shared<OpenCvLens>(calibration);
}

}  // namespace lp
