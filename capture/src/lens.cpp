#include "liveprobe/capture/lens.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/core/utility.hpp>
#include <optional>

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

/// A mirror ball the camera sees (the circle of its silhouette known): each camera ray that
/// meets the ball reflects off it, traced as it is, at the distance the circle's size implies.
/// Camera rays are in OpenCV's camera frame; reflected directions in the mirror-ball layout's
/// world (liveprobe/sh/layout.h): the ray to the ball's centre is +x, the camera's right
/// (orthogonal to it) -y, its up +z. With the ball's radius 1 its centre is at distance
/// D = 1 / sin(alpha), alpha the silhouette's angular radius. Unseen: the cone behind the ball
/// (within alpha of +x) and the camera's own reflection (within alpha of -x: a camera about the
/// ball's size).
class Mirror {
 public:
  Mirror(const glm::dvec3& towardsCentre, double alpha)
      : v_(glm::normalize(towardsCentre)), alpha_(alpha), distance_(1.0 / std::sin(alpha)) {
    const glm::dvec3 right = glm::normalize(glm::dvec3(1, 0, 0) - v_.x * v_);
    const glm::dvec3 up = glm::cross(right, v_);  // about camera -y, orthogonal to v and right
    // World from camera: a ray's coordinates along (right, up, v), sent to -y, +z, +x.
    const glm::dmat3 basis(right, up, v_);
    const glm::dmat3 local(glm::dvec3(0, -1, 0), glm::dvec3(0, 0, 1), glm::dvec3(1, 0, 0));
    worldFromCamera_ = local * glm::transpose(basis);
  }

  /// The world direction camera ray d sees in the ball; none off the ball or in the unseen cones.
  std::optional<glm::dvec3> reflect(const glm::dvec3& ray) const {
    const glm::dvec3 d = glm::normalize(ray);
    const double b = glm::dot(d, v_) * distance_;
    const double disc = b * b - (distance_ * distance_ - 1.0);
    if (!(disc >= 0) || b <= 0) return std::nullopt;
    const glm::dvec3 n = (b - std::sqrt(disc)) * d - distance_ * v_;
    const glm::dvec3 r = d - 2.0 * glm::dot(d, n) * n;
    if (!seen(r)) return std::nullopt;
    return worldFromCamera_ * r;
  }

  /// The camera ray whose reflection is world direction w; none where the ball shows no such
  /// reflection. The normal lies in the plane of the ball's axis and w: found by bisection on its
  /// angle from the axis, along which the reflection's angle from the camera grows monotonically.
  std::optional<glm::dvec3> source(const glm::dvec3& w) const {
    const glm::dvec3 r = glm::normalize(glm::transpose(worldFromCamera_) * w);
    if (!seen(r)) return std::nullopt;
    const double target = std::acos(std::clamp(-glm::dot(r, v_), -1.0, 1.0));
    glm::dvec3 side = r - glm::dot(r, v_) * v_;
    if (glm::length(side) < 1e-12) return std::nullopt;
    side = glm::normalize(side);
    const auto ray = [&](double phi) {
      const glm::dvec3 n = -std::cos(phi) * v_ + std::sin(phi) * side;
      return glm::normalize(distance_ * v_ + n);
    };
    const auto angle = [&](double phi) {
      const glm::dvec3 n = -std::cos(phi) * v_ + std::sin(phi) * side, d = ray(phi);
      const glm::dvec3 out = d - 2.0 * glm::dot(d, n) * n;
      return std::acos(std::clamp(-glm::dot(out, v_), -1.0, 1.0));
    };
    double lo = 0, hi = std::acos(1.0 / distance_);
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (lo + hi);
      (angle(mid) < target ? lo : hi) = mid;
    }
    return ray(0.5 * (lo + hi));
  }

 private:
  bool seen(const glm::dvec3& r) const {
    const double c = std::cos(alpha_);
    return glm::dot(r, v_) < c && -glm::dot(r, v_) < c;
  }
  glm::dvec3 v_;
  double alpha_, distance_;
  glm::dmat3 worldFromCamera_;
};

/// A calibration as a LensModel. Points go through OpenCV in normalised coordinates (the camera
/// matrix applied here, skew included, with OpenCV's pixel centres at whole numbers), so both
/// models see the same K.
class OpenCvLens final : public LensModel {
 public:
  explicit OpenCvLens(LensCalibration c, std::optional<glm::vec3> ball = std::nullopt)
      : c_(std::move(c)), d_(c_.distortion), ball_(ball) {}

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
    return std::string(ball_ ? "a mirror ball through the " : "") +
           (c_.model == LensCalibration::Model::Fisheye ? "fisheye" : "pinhole") + " lens " +
           c_.source;
  }

  std::vector<SphereSample> samples(int width, int height) const override {
    const Intrinsics k = at(width);
    const std::optional<Mirror> mirror = mirrorAt(k);
    // A camera ray as what the pixel measures: the ray itself, or its reflection in the ball;
    // (0, 0, 0) for nothing.
    const auto outward = [&](const glm::dvec3& d) {
      if (!valid(d)) return glm::dvec3(0.0);
      if (!mirror) return d;
      return mirror->reflect(d).value_or(glm::dvec3(0.0));
    };
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
        for (std::size_t x = 0; x <= w; ++x)
          corners[std::size_t(y) * (w + 1) + x] = outward(dirs[x]);
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
          const glm::dvec3 centre = outward(dirs[x]);
          if (!known(centre) || !known(a) || !known(b) || !known(d) || !known(e)) {
            s = {glm::vec3(0, 0, 1), 0.0f};
            continue;
          }
          // The corners in order round the pixel: a b (top), e d (bottom).
          s = {glm::vec3(centre), float(triangle(a, b, e) + triangle(a, e, d))};
        }
      }
    });
    return out;
  }

  void pixels(int width, int height, const glm::vec3* dirs, std::size_t count,
              glm::vec2* out) const override {
    const Intrinsics k = at(width);
    const std::optional<Mirror> mirror = mirrorAt(k);
    std::vector<cv::Point3d> ahead;
    std::vector<std::size_t> which;
    for (std::size_t i = 0; i < count; ++i) {
      out[i] = glm::vec2(NAN);
      glm::dvec3 d(dirs[i]);
      if (mirror) {
        const auto ray = mirror->source(d);
        if (!ray) continue;
        d = *ray;
      }
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
  static bool known(const glm::dvec3& d) { return glm::dot(d, d) > 0.5; }

  /// The ball in a frame of these intrinsics: the ray to its circle's centre, and its angular
  /// radius, the mean over eight points of the circle's rim.
  std::optional<Mirror> mirrorAt(const Intrinsics& k) const {
    if (!ball_) return std::nullopt;
    std::vector<cv::Point2d> pts{k.normalise(ball_->x, ball_->y)};
    for (int i = 0; i < 8; ++i)
      pts.push_back(k.normalise(ball_->x + ball_->z * std::cos(i * kHalfPi / 2),
                                ball_->y + ball_->z * std::sin(i * kHalfPi / 2)));
    std::vector<glm::dvec3> dirs;
    directions(pts, k, dirs);
    double alpha = 0;
    for (std::size_t i = 0; i < pts.size(); ++i)
      if (!valid(dirs[i]))
        throw Error(describe() + ": the mirror ball's circle reaches where the lens sees nothing");
    for (std::size_t i = 1; i < pts.size(); ++i)
      alpha += std::acos(std::clamp(glm::dot(dirs[0], dirs[i]), -1.0, 1.0)) / 8;
    if (!(alpha > 1e-4 && alpha < 1.4))
      throw Error(describe() + ": the mirror ball's circle is not a ball in front of the camera");
    return Mirror(dirs[0], alpha);
  }

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
  std::optional<glm::vec3> ball_;  ///< the mirror ball's circle, pixels (centres at +0.5)
};

}  // namespace

std::shared_ptr<const LensModel> makeLensModel(const LensCalibration& calibration) {
  return std::make_shared<OpenCvLens>(calibration);
}

std::shared_ptr<const LensModel> makeBallModel(const LensCalibration& camera, glm::vec3 circle) {
  return std::make_shared<OpenCvLens>(camera, circle);
}

double seenRadius(const LensCalibration& calibration, int width, int height) {
  const std::vector<SphereSample> samples = makeLensModel(calibration)->samples(width, height);
  // The principal point in this frame's pixels (OpenCV's centres are whole numbers; ours +0.5).
  const double cx = calibration.K[2] * width / calibration.width + 0.5,
               cy = calibration.K[5] * height / calibration.height + 0.5;
  double nearest = HUGE_VAL;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      if (samples[std::size_t(y) * std::size_t(width) + std::size_t(x)].solidAngle == 0.0f)
        nearest = std::min(nearest, std::hypot(x + 0.5 - cx, y + 0.5 - cy));
  return nearest == HUGE_VAL ? 0.0 : nearest;
}

}  // namespace lp
