// Lens calibrations as the ecosystem writes them: OpenCV's FileStorage (YAML and JSON, written
// here by cv::FileStorage itself) and ROS's camera_info YAML (as camera_calibration writes it)
// read to the same lens; every fault of a bad file refused in one line naming the file.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "liveprobe/capture/image.h"
#include "liveprobe/capture/lens.h"
#include "liveprobe/capture/lens_calibrate.h"
#include "liveprobe/frame/srgb.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/lights.h"
#include "liveprobe/sh/projector.h"
#include "sh_compare.h"
#include "test_util.h"

namespace {

namespace fs = std::filesystem;
using lp::LensCalibration;

const cv::Matx33d kK(410.5, 0, 641.25, 0, 409.75, 478.5, 0, 0, 1);
const std::vector<double> kFisheye = {0.021, -0.0043, 0.0012, -0.00021};

void writeOpenCv(const std::string& path, const std::string& model, const std::vector<double>& d) {
  cv::FileStorage fs(path, cv::FileStorage::WRITE);
  fs << "image_width" << 1280 << "image_height" << 960;
  fs << "camera_matrix" << cv::Mat(kK);
  fs << "distortion_coefficients" << cv::Mat(d).t();
  fs << "distortion_model" << model;
}

void expectTheLens(const LensCalibration& l, LensCalibration::Model model,
                   const std::vector<double>& d) {
  EXPECT_EQ(l.model, model);
  EXPECT_EQ(l.width, 1280);
  EXPECT_EQ(l.height, 960);
  for (int i = 0; i < 9; ++i) EXPECT_DOUBLE_EQ(l.K[std::size_t(i)], kK.val[i]) << i;
  EXPECT_EQ(l.distortion, d);
}

TEST(Lens, OpenCvAndRosFilesReadToTheSameLens) {
  lpt::TempDir tmp;
  for (const char* ext : {".yaml", ".yml", ".json"}) {
    const std::string f = (tmp.path / (std::string("fisheye") + ext)).string();
    writeOpenCv(f, "fisheye", kFisheye);
    expectTheLens(lp::readLensCalibration(f), LensCalibration::Model::Fisheye, kFisheye);
  }
  const std::vector<double> plumb = {-0.28, 0.07, 0.0002, -0.0001, 0.0};
  writeOpenCv((tmp.path / "pinhole.yaml").string(), "plumb_bob", plumb);
  expectTheLens(lp::readLensCalibration((tmp.path / "pinhole.yaml").string()),
                LensCalibration::Model::Pinhole, plumb);
  // ROS camera_info, as camera_calibration writes it: plain maps, no OpenCV tags, no header.
  std::ofstream(tmp.path / "ros.yaml") << "image_width: 1280\n"
                                          "image_height: 960\n"
                                          "camera_name: sky\n"
                                          "camera_matrix:\n"
                                          "  rows: 3\n"
                                          "  cols: 3\n"
                                          "  data: [410.5, 0, 641.25, 0, 409.75, 478.5, 0, 0, 1]\n"
                                          "distortion_model: equidistant\n"
                                          "distortion_coefficients:\n"
                                          "  rows: 1\n"
                                          "  cols: 4\n"
                                          "  data: [0.021, -0.0043, 0.0012, -0.00021]\n"
                                          "rectification_matrix:\n"
                                          "  rows: 3\n"
                                          "  cols: 3\n"
                                          "  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n";
  expectTheLens(lp::readLensCalibration((tmp.path / "ros.yaml").string()),
                LensCalibration::Model::Fisheye, kFisheye);
}

TEST(Lens, ABadFileIsOneLineNamingIt) {
  lpt::TempDir tmp;
  const std::string good =
      "%YAML:1.0\n---\nimage_width: 1280\nimage_height: 960\n"
      "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
      "   data: [ 410.5, 0., 641.25, 0., 409.75, 478.5, 0., 0., 1. ]\n"
      "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 4\n   dt: d\n"
      "   data: [ 0.021, -0.0043, 0.0012, -0.00021 ]\n"
      "distortion_model: fisheye\n";
  const std::string f = (tmp.path / "lens.yaml").string();
  std::ofstream(f) << good;
  ASSERT_NO_THROW(lp::readLensCalibration(f));
  const auto refused = [&](const std::string& from, const std::string& to, const char* says) {
    std::string text = good;
    const auto at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    std::ofstream(f) << text;
    try {
      lp::readLensCalibration(f);
      ADD_FAILURE() << "accepted, with " << to;
    } catch (const lp::Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(f + ": ", 0), 0u) << what;
      EXPECT_NE(what.find(says), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  };
  refused("image_width: 1280\n", "", "no image_width");
  refused("image_height: 960", "image_height: -4", "image_height must be");
  refused("410.5, 0., 641.25", "0., 0., 641.25", "no positive focal length");
  refused("0., 0., 1. ]", "0., 1., 1. ]", "last row must be 0 0 1");
  refused("409.75", ".nan", "not finite");
  refused("rows: 3\n   cols: 3", "rows: 2\n   cols: 3", "camera_matrix says 2x3");
  refused("cols: 4\n   dt: d\n   data: [ 0.021, -0.0043, 0.0012, -0.00021 ]",
          "cols: 5\n   dt: d\n   data: [ 0.021, -0.0043, 0.0012, -0.00021, 0.1 ]",
          "has 4 distortion coefficients, not 5");
  refused("distortion_model: fisheye", "distortion_model: kannala", "is not one liveprobe reads");
  refused("distortion_model: fisheye", "", "no distortion_model");
  std::ofstream(f) << "image_width: [1280\n";
  EXPECT_THROW(lp::readLensCalibration(f), lp::Error);
  EXPECT_THROW(lp::readLensCalibration((tmp.path / "none.yaml").string()), lp::Error);
}

// ---- Frames through a known lens ---------------------------------------------------------
// A Kannala-Brandt fisheye (cv::fisheye's model) of 1280x960 that sees a little more than the
// hemisphere in its frame; the frames are made from a map of ../shared/data with the lens solved
// here (Newton on theta_d(theta), checked against cv::fisheye::distortPoints), and the truth is
// the map's own pixels: what the lens sees, plus the declared fill of the rest.

struct KannalaBrandt {
  double fx = 285, fy = 286.5, cx = 641.3, cy = 478.6;
  double k[4] = {0.021, -0.0043, 0.0012, -0.00021};
  double thetaD(double t) const {
    const double t2 = t * t;
    return t * (1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
  }
  double slope(double t) const {
    const double t2 = t * t;
    return 1 + t2 * (3 * k[0] + t2 * (5 * k[1] + t2 * (7 * k[2] + t2 * 9 * k[3])));
  }
  /// The camera-frame direction of OpenCV pixel coordinates (x, y); none past 90 degrees.
  std::optional<glm::dvec3> direction(double x, double y) const {
    const double u = (x - cx) / fx, v = (y - cy) / fy, rd = std::hypot(u, v);
    if (rd >= thetaD(kPi / 2)) return std::nullopt;
    double t = rd;
    for (int i = 0; i < 20; ++i) t -= (thetaD(t) - rd) / slope(t);
    if (rd < 1e-12) return glm::dvec3(0, 0, 1);
    return glm::dvec3(std::sin(t) * u / rd, std::sin(t) * v / rd, std::cos(t));
  }
  std::string write(const std::string& path) const {
    cv::FileStorage fs(path, cv::FileStorage::WRITE);
    fs << "image_width" << 1280 << "image_height" << 960;
    fs << "camera_matrix" << cv::Mat(cv::Matx33d(fx, 0, cx, 0, fy, cy, 0, 0, 1));
    fs << "distortion_coefficients" << cv::Mat(std::vector<double>(k, k + 4)).t();
    fs << "distortion_model"
       << "fisheye";
    return path;
  }
  static constexpr double kPi = 3.14159265358979323846;
};

/// Bilinear radiance of an equirect map in world direction d.
glm::vec3 mapAt(const lp::Image& map, glm::dvec3 d) {
  const glm::vec2 at = *lp::layoutPixel(lp::Layout::Equirect, map.width, map.height, glm::vec3(d));
  const float x = at.x - 0.5f, y = std::clamp(at.y - 0.5f, 0.0f, float(map.height - 1));
  const int x0 = int(std::floor(x)), y0 = int(y), y1 = std::min(y0 + 1, map.height - 1);
  const float fx = x - float(x0), fy = y - float(y0);
  const auto px = [&](int xx, int yy) {
    xx = ((xx % map.width) + map.width) % map.width;
    const float* p = &map.rgb[3 * (std::size_t(yy) * map.width + std::size_t(xx))];
    return glm::vec3(p[0], p[1], p[2]);
  };
  return glm::mix(glm::mix(px(x0, y0), px(x0 + 1, y0), fx),
                  glm::mix(px(x0, y1), px(x0 + 1, y1), fx), fy);
}

/// A 1280x960 frame of `map` through the lens, the camera turned by `world` (world from camera):
/// each pixel the mean of 2x2 directions across it.
lp::Image fisheyeFrame(const lp::Image& map, const KannalaBrandt& lens, const glm::dmat3& world) {
  lp::Image frame;
  frame.width = 1280, frame.height = 960;
  frame.rgb.assign(3 * std::size_t(frame.width) * frame.height, 0.0f);
  for (int y = 0; y < frame.height; ++y)
    for (int x = 0; x < frame.width; ++x) {
      glm::vec3 sum(0.0f);
      for (const double a : {-0.25, 0.25})
        for (const double b : {-0.25, 0.25})
          if (auto d = lens.direction(x + a, y + b)) sum += mapAt(map, world * *d) / 4.0f;
      std::copy(&sum[0], &sum[0] + 3, &frame.rgb[3 * (std::size_t(y) * frame.width + x)]);
    }
  return frame;
}

/// The truth in the camera's frame: the map where the lens sees (within 90 degrees of its
/// axis), and elsewhere the fill: with `ground`, below the world's horizon albedo E_up / pi and
/// above it the nearest seen direction (on the 90-degree cone); without, nothing.
lp::Sh9 truth(const lp::Image& map, const glm::dmat3& world, bool ground, double albedo) {
  const auto samples = lp::equirectSamples(map.width, map.height);
  const glm::dvec3 up = glm::transpose(world) * glm::dvec3(0, 0, 1);
  std::array<glm::dvec3, 9> seen{}, sky{};
  std::array<double, 9> below{};
  glm::dvec3 eUp(0.0);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const glm::dvec3 d = glm::transpose(world) * glm::dvec3(samples[i].dir);
    const double dw = samples[i].solidAngle;
    const auto y = lp::shBasis(glm::vec3(d));
    if (d.z > 0) {
      const glm::dvec3 l(map.rgb[3 * i], map.rgb[3 * i + 1], map.rgb[3 * i + 2]);
      for (int k = 0; k < 9; ++k) seen[k] += l * double(y[k]) * dw;
      eUp += l * std::max(0.0, glm::dot(d, up)) * dw;
    } else if (glm::dot(d, up) < 0) {
      for (int k = 0; k < 9; ++k) below[k] += double(y[k]) * dw;
    } else {
      const glm::dvec3 edge = glm::normalize(glm::dvec3(d.x, d.y, 0.0));
      const glm::dvec3 l(mapAt(map, world * edge));
      for (int k = 0; k < 9; ++k) sky[k] += l * double(y[k]) * dw;
      eUp += l * glm::dot(d, up) * dw;
    }
  }
  lp::Sh9 out;
  for (int k = 0; k < 9; ++k)
    out.c[k] = glm::vec3(seen[k] + (ground ? sky[k] + albedo * eUp / KannalaBrandt::kPi * below[k]
                                           : glm::dvec3(0.0)));
  return out;
}

using lpt::worstOfL00;

glm::dmat3 tilt(double degrees) {  // about the world's x axis
  const double a = glm::radians(degrees);
  return glm::dmat3(glm::dvec3(1, 0, 0), glm::dvec3(0, std::cos(a), std::sin(a)),
                    glm::dvec3(0, -std::sin(a), std::cos(a)));
}

/// The test's lens as liveprobe reads it: written as a calibration file, read back.
struct FisheyeCamera {
  lpt::TempDir tmp;
  KannalaBrandt kb;
  lp::LayoutSpec spec{lp::Layout::Lens};
  FisheyeCamera() {
    spec.lens =
        lp::makeLensModel(lp::readLensCalibration(kb.write((tmp.path / "sky.yaml").string())));
  }
  lp::Image frame;
  /// The map through the camera straight up, then tilted 35 degrees: f(degrees, world from
  /// camera, the frame's view).
  template <class F>
  void eachTilt(const lp::Image& map, F f) {
    for (const double degrees : {0.0, 35.0}) {
      const glm::dmat3 world = tilt(degrees);
      frame = fisheyeFrame(map, kb, world);
      f(degrees, world,
        lp::PanoramaView::rgbF32(frame.rgb.data(), frame.width, frame.height, spec));
    }
  }
};

TEST(Lens, TheTestsLensIsOpenCvsFisheye) {
  // The frames' own lens solver against OpenCV's forward model.
  const KannalaBrandt lens;
  const cv::Matx33d K(lens.fx, 0, lens.cx, 0, lens.fy, lens.cy, 0, 0, 1);
  std::vector<cv::Point2d> undistorted, distorted, pixels;
  for (const auto& [x, y] :
       {std::pair{200.0, 480.0}, {640.0, 20.0}, {900.5, 700.25}, {641.3, 478.6}}) {
    const glm::dvec3 d = *lens.direction(x, y);
    undistorted.emplace_back(d.x / d.z, d.y / d.z);
    pixels.emplace_back(x, y);
  }
  cv::fisheye::distortPoints(undistorted, distorted, K, std::vector<double>(lens.k, lens.k + 4));
  for (std::size_t i = 0; i < pixels.size(); ++i)
    EXPECT_LT(cv::norm(distorted[i] - pixels[i]), 1e-6) << pixels[i];
}

TEST(Lens, AFisheyeSkyIsTheMapsSeenHemispherePlusTheDeclaredFill) {
  const lp::Image map = lp::loadImage(lpt::dataPath("equirect/pedestrian_overpass_1k.hdr"));
  FisheyeCamera camera;
  lp::LayoutSpec& spec = camera.spec;
  camera.eachTilt(map, [&](double degrees, const glm::dmat3& world, const lp::PanoramaView& view) {
    spec.unseen.up = glm::vec3(glm::transpose(world) * glm::dvec3(0, 0, 1));
    spec.unseen.fill = lp::UnseenRule::Fill::Ground;
    const lp::Projector ground(spec, view.width, view.height);
    EXPECT_NEAR(ground.coverage(), 0.5, 0.002) << degrees;  // the rim's pixels past 90: unseen
    EXPECT_LT(worstOfL00(ground.project(view), truth(map, world, true, 0.2)), 0.005) << degrees;
    spec.unseen.fill = lp::UnseenRule::Fill::Black;
    const lp::Projector black(spec, view.width, view.height);
    EXPECT_LT(worstOfL00(black.project(view), truth(map, world, false, 0.2)), 0.005) << degrees;
  });
}

// A webcam's lens (cv::calibrateCamera's plumb_bob: 70 degrees across, barrel distortion):
// the frame made with OpenCV's undistortPoints (checked against its forward projectPoints), the
// truth the map's pixels whose directions projectPoints lands inside the frame, nothing else
// (--unseen black): within 0.5% of the seen part's L00, tilted or not.
TEST(Lens, APinholeFrameIsTheMapsPixelsItSees) {
  const lp::Image map = lp::loadImage(lpt::dataPath("equirect/pedestrian_overpass_1k.hdr"));
  const cv::Matx33d K(900.5, 0, 641.3, 0, 899.0, 478.6, 0, 0, 1);
  const std::vector<double> dist = {-0.28, 0.08, 0.0005, -0.0003, -0.01};
  constexpr int kW = 1280, kH = 960;
  lpt::TempDir tmp;
  const std::string file = tmp / "webcam.yaml";
  {
    cv::FileStorage fs(file, cv::FileStorage::WRITE);
    fs << "image_width" << kW << "image_height" << kH << "camera_matrix" << cv::Mat(K);
    fs << "distortion_coefficients" << cv::Mat(dist).t() << "distortion_model"
       << "plumb_bob";
  }
  lp::LayoutSpec spec(lp::Layout::Lens);
  spec.lens = lp::makeLensModel(lp::readLensCalibration(file));
  spec.unseen.fill = lp::UnseenRule::Fill::Black;
  // Each pixel's centre's ray (OpenCV coordinates: pixel centres whole), undistorted (a pixel
  // is a fifth of the map's: one ray a pixel is within 0.01% of 2x2).
  std::vector<cv::Point2d> at, normal;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) at.emplace_back(x, y);
  cv::undistortPoints(
      at, normal, K, dist, cv::noArray(), cv::noArray(),
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-14));
  {  // the rays land where they came from
    std::vector<cv::Point3d> rays;
    std::vector<cv::Point2d> back;
    for (std::size_t i = 0; i < at.size(); i += 9973)
      rays.emplace_back(normal[i].x, normal[i].y, 1);
    cv::projectPoints(rays, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, dist, back);
    for (std::size_t i = 0, j = 0; i < at.size(); i += 9973, ++j)
      ASSERT_LT(cv::norm(back[j] - at[i]), 1e-3) << at[i];
  }
  for (const double degrees : {0.0, 35.0}) {
    const glm::dmat3 world = tilt(degrees);
    lp::Image frame(kW, kH);
    for (std::size_t p = 0; p < std::size_t(kW) * kH; ++p) {
      const glm::vec3 l =
          mapAt(map, world * glm::normalize(glm::dvec3(normal[p].x, normal[p].y, 1.0)));
      std::copy(&l[0], &l[0] + 3, &frame.rgb[3 * p]);
    }
    // The truth: the map's own pixels whose centres the lens images inside the frame. (Past the
    // radius where the radial distortion turns back, r (1 + k1 r^2 + k2 r^4 + k3 r^6) falls again
    // and projectPoints folds directions the lens does not see back into the frame.)
    const auto samples = lp::equirectSamples(map.width, map.height);
    double turn = 0;
    while (1 + 3 * dist[0] * turn * turn + 5 * dist[1] * std::pow(turn, 4) +
               7 * dist[4] * std::pow(turn, 6) >
           0)
      turn += 1e-3;
    std::vector<cv::Point3d> dirs;
    std::vector<std::size_t> index;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const glm::dvec3 d = glm::transpose(world) * glm::dvec3(samples[i].dir);
      if (d.z > 0 && std::hypot(d.x, d.y) < turn * d.z)
        dirs.emplace_back(d.x, d.y, d.z), index.push_back(i);
    }
    std::vector<cv::Point2d> px;
    cv::projectPoints(dirs, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, dist, px);
    std::array<glm::dvec3, 9> seen{};
    for (std::size_t j = 0; j < dirs.size(); ++j) {
      if (!(px[j].x >= -0.5 && px[j].x < kW - 0.5 && px[j].y >= -0.5 && px[j].y < kH - 0.5))
        continue;
      const std::size_t i = index[j];
      const glm::dvec3 l(map.rgb[3 * i], map.rgb[3 * i + 1], map.rgb[3 * i + 2]);
      const auto y =
          lp::shBasis(glm::vec3(glm::normalize(glm::dvec3(dirs[j].x, dirs[j].y, dirs[j].z))));
      for (int k = 0; k < 9; ++k) seen[k] += l * double(y[k]) * double(samples[i].solidAngle);
    }
    lp::Sh9 want;
    for (int k = 0; k < 9; ++k) want.c[k] = glm::vec3(seen[k]);
    const lp::Projector projector(spec, kW, kH);
    const lp::Sh9 got = projector.project(lp::PanoramaView::rgbF32(frame.rgb.data(), kW, kH, spec));
    std::printf("pinhole, %.0f degrees: %.3f%% of the seen part's L00, coverage %.4f\n", degrees,
                100 * worstOfL00(got, want), projector.coverage());
    EXPECT_LT(worstOfL00(got, want), 0.005) << degrees;
  }
}

// --unseen mean against a map whose edge is known: radiance a + b z + c x in the camera's frame
// (per channel), so the seen hemisphere's rim (z = 0) averages a whatever the tilt; the truth is
// the map's pixels where the lens sees plus a over the rest.
TEST(Lens, TheMeanFillIsTheMeanRadianceOfTheSeenEdge) {
  FisheyeCamera camera;
  camera.spec.unseen.fill = lp::UnseenRule::Fill::Mean;
  const glm::dvec3 a(1.0, 0.8, 0.5), b(0.6, 0.5, 0.4), c(0.3, -0.2, 0.1);
  for (const double degrees : {0.0, 35.0}) {
    const glm::dmat3 world = tilt(degrees);
    lp::Image map(1024, 512);
    const auto samples = lp::equirectSamples(map.width, map.height);
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const glm::dvec3 d = glm::transpose(world) * glm::dvec3(samples[i].dir);
      const glm::dvec3 l = a + b * d.z + c * d.x;
      for (int ch = 0; ch < 3; ++ch) map.rgb[3 * i + std::size_t(ch)] = float(l[ch]);
    }
    std::array<glm::dvec3, 9> sum{};
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const glm::dvec3 d = glm::transpose(world) * glm::dvec3(samples[i].dir);
      const glm::dvec3 l =
          d.z > 0 ? glm::dvec3(map.rgb[3 * i], map.rgb[3 * i + 1], map.rgb[3 * i + 2]) : a;
      const auto y = lp::shBasis(glm::vec3(d));
      for (int k = 0; k < 9; ++k) sum[k] += l * double(y[k]) * double(samples[i].solidAngle);
    }
    lp::Sh9 want;
    for (int k = 0; k < 9; ++k) want.c[k] = glm::vec3(sum[k]);
    const lp::Image frame = fisheyeFrame(map, camera.kb, world);
    const lp::Projector projector(camera.spec, frame.width, frame.height);
    const lp::Sh9 got = projector.project(
        lp::PanoramaView::rgbF32(frame.rgb.data(), frame.width, frame.height, camera.spec));
    std::printf("mean fill, %.0f degrees: %.3f%% of L00\n", degrees, 100 * worstOfL00(got, want));
    EXPECT_LT(worstOfL00(got, want), 0.005) << degrees;
  }
}

TEST(Lens, TheProjectionCountsEachPixelWithTheWeightsAGpuUploads) {
  // The CPU projects a lens frame from each pixel's direction and solid angle, plus one sum for
  // the ground and extra weights on the edge; Projector::blockedWeights() holds every pixel's
  // nine weights whole (what the GPU uploads). The two agree for every fill, on a packed frame
  // and on one whose rows are padded.
  const lp::Image map = lp::loadImage(lpt::dataPath("equirect/quarry_01_1k.hdr"));
  FisheyeCamera camera;
  const glm::dmat3 world = tilt(35.0);
  const lp::Image frame = fisheyeFrame(map, camera.kb, world);
  const std::size_t w = std::size_t(frame.width), h = std::size_t(frame.height);
  std::vector<float> strided(h * (3 * w + 9), -1.0f);
  for (std::size_t y = 0; y < h; ++y)
    std::copy_n(frame.rgb.data() + 3 * w * y, 3 * w, strided.data() + (3 * w + 9) * y);
  lp::LayoutSpec spec = camera.spec;
  spec.unseen.up = glm::vec3(glm::transpose(world) * glm::dvec3(0, 0, 1));
  for (const auto fill : {lp::UnseenRule::Fill::Ground, lp::UnseenRule::Fill::Mean}) {
    spec.unseen.fill = fill;
    const lp::Projector projector(spec, frame.width, frame.height);
    const auto& blocked = projector.blockedWeights();
    std::array<glm::dvec3, 9> want{};
    for (std::size_t p = 0; p < w * h; ++p)
      for (int k = 0; k < 9; ++k)
        want[k] += glm::dvec3(frame.rgb[3 * p], frame.rgb[3 * p + 1], frame.rgb[3 * p + 2]) *
                   double(blocked[((p / 16) * 9 + std::size_t(k)) * 16 + p % 16]);
    auto view = lp::PanoramaView::rgbF32(frame.rgb.data(), frame.width, frame.height, spec);
    const lp::Sh9 packed = projector.project(view);
    view.data = strided.data();
    view.rowStride = (3 * w + 9) * sizeof(float);
    const lp::Sh9 padded = projector.project(view);
    for (int k = 0; k < 9; ++k)
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(packed.c[k][c], want[k][c], 2e-6 * want[0][c]) << k << " " << c;
        EXPECT_NEAR(padded.c[k][c], want[k][c], 2e-6 * want[0][c]) << k << " " << c;
      }
  }
}

TEST(Lens, TheSunThroughAFisheyeIsWhereTheMapHasIt) {
  const lp::Image map = lp::loadImage(lpt::dataPath("equirect/quarry_01_1k.hdr"));
  // The map's sun: the luminance-weighted centre of its pixels above half the peak.
  const auto samples = lp::equirectSamples(map.width, map.height);
  const auto lum = [&](std::size_t i) {
    return 0.2126 * map.rgb[3 * i] + 0.7152 * map.rgb[3 * i + 1] + 0.0722 * map.rgb[3 * i + 2];
  };
  double peak = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) peak = std::max(peak, lum(i));
  glm::dvec3 sun(0.0);
  for (std::size_t i = 0; i < samples.size(); ++i)
    if (lum(i) > peak / 2)
      sun += glm::dvec3(samples[i].dir) * lum(i) * double(samples[i].solidAngle);
  sun = glm::normalize(sun);
  FisheyeCamera camera;
  camera.eachTilt(map, [&](double degrees, const glm::dmat3& world, const lp::PanoramaView& view) {
    const lp::Projector projector(camera.spec, view.width, view.height);
    std::vector<float> peaks;
    const lp::Sh9 whole = projector.project(view, nullptr, &peaks);
    const lp::LightSplit split = lp::LightExtractor(projector).extract(view, whole, peaks, {});
    ASSERT_EQ(split.lights.size(), 1u) << degrees;
    const glm::dvec3 want = glm::transpose(world) * sun;  // in the camera's frame
    EXPECT_LT(
        glm::degrees(std::acos(std::min(1.0, glm::dot(want, glm::dvec3(split.lights[0].dir))))),
        0.5)
        << degrees;
  });
}

// ---- A mirror ball filmed through the lens ---------------------------------------------------

TEST(Lens, AMirrorBallFourRadiiFromTheCameraIsTracedAsItIs) {
  // The tests' fisheye films a chrome ball on its axis 4 radii away (its silhouette 14.5 degrees
  // across); around it the room the lens sees directly. Each pixel is the mean of 2x2 rays, each
  // met with the sphere and reflected here. The world is the mirror ball's: the ray to the ball
  // +x, the camera's right -y, its up +z. The map (quarry_01) is turned so its sun lies 90
  // degrees from the camera's line of sight. Truth: the whole map's coefficients, and its sun.
  const lp::Image source = lp::loadImage(lpt::dataPath("equirect/quarry_01_1k.hdr"));
  const auto samples = lp::equirectSamples(source.width, source.height);
  const auto lum = [&](const lp::Image& m, std::size_t i) {
    return 0.2126 * m.rgb[3 * i] + 0.7152 * m.rgb[3 * i + 1] + 0.0722 * m.rgb[3 * i + 2];
  };
  const auto sunOf = [&](const lp::Image& m) {
    double peak = 0;
    for (std::size_t i = 0; i < samples.size(); ++i) peak = std::max(peak, lum(m, i));
    glm::dvec3 sun(0.0);
    for (std::size_t i = 0; i < samples.size(); ++i)
      if (lum(m, i) > peak / 2)
        sun += glm::dvec3(samples[i].dir) * lum(m, i) * double(samples[i].solidAngle);
    return glm::normalize(sun);
  };
  const glm::dvec3 sun0 = sunOf(source);
  const double yaw = glm::radians(90.0) - std::atan2(sun0.y, sun0.x);
  const glm::dmat3 turn(glm::dvec3(std::cos(yaw), std::sin(yaw), 0),
                        glm::dvec3(-std::sin(yaw), std::cos(yaw), 0), glm::dvec3(0, 0, 1));
  lp::Image map = source;  // the map turned about z: world direction d reads source at turn^T d
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const glm::vec3 l = mapAt(source, glm::transpose(turn) * glm::dvec3(samples[i].dir));
    std::copy(&l[0], &l[0] + 3, &map.rgb[3 * i]);
  }
  const glm::dvec3 sun = sunOf(map);

  const KannalaBrandt kb;
  const auto world = [](const glm::dvec3& c) { return glm::dvec3(c.z, -c.x, -c.y); };
  // The frame of a ball `distance` radii away that reflects `reflectance` of the light, and the
  // radius of its silhouette in pixels.
  const auto render = [&](double distance, float reflectance, double& rimPx) {
    lp::Image frame;
    frame.width = 1280, frame.height = 960;
    frame.rgb.assign(3 * std::size_t(frame.width) * frame.height, 0.0f);
    // The ball's pixels each span some 20 of the map's: 6x6 rays there, so the map's sun is not
    // missed or caught whole by a few rays; 2x2 elsewhere.
    rimPx = (kb.fx + kb.fy) / 2 * kb.thetaD(std::asin(1.0 / distance));
    for (int y = 0; y < frame.height; ++y)
      for (int x = 0; x < frame.width; ++x) {
        const int n = std::hypot(x - kb.cx, y - kb.cy) < rimPx + 2 ? 6 : 2;
        glm::vec3 sum(0.0f);
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j) {
            const auto ray = kb.direction(x - 0.5 + (j + 0.5) / n, y - 0.5 + (i + 0.5) / n);
            if (!ray) continue;
            const glm::dvec3 d = *ray, centre(0, 0, distance);
            const double along = glm::dot(d, centre),
                         disc = along * along - (distance * distance - 1);
            const glm::dvec3 n0 = (along - std::sqrt(std::max(disc, 0.0))) * d - centre;
            // Off the ball: the room around it; on it, the reflection.
            sum += (disc < 0 ? mapAt(map, world(d))
                             : reflectance * mapAt(map, world(d - 2.0 * glm::dot(d, n0) * n0))) /
                   float(n * n);
          }
        std::copy(&sum[0], &sum[0] + 3, &frame.rgb[3 * (std::size_t(y) * frame.width + x)]);
      }
    return frame;
  };
  const double distance = 4.0, alpha = std::asin(1.0 / distance);
  double rimPx = 0;
  const lp::Image frame = render(distance, 1.0f, rimPx);
  lpt::TempDir tmp;
  const glm::vec3 circle(float(kb.cx + 0.5), float(kb.cy + 0.5), float(rimPx));
  lp::LayoutSpec traced(lp::Layout::MirrorBall), far(lp::Layout::MirrorBall);
  traced.circle = far.circle = circle;
  traced.lens = lp::makeBallModel(
      lp::readLensCalibration(kb.write((tmp.path / "cam.yaml").string())), circle);
  const auto view = [&](const lp::LayoutSpec& spec) {
    return lp::PanoramaView::rgbF32(frame.rgb.data(), frame.width, frame.height, spec);
  };
  const lp::Sh9 want =
      lp::Projector(lp::Layout::Equirect, map.width, map.height)
          .project(lp::PanoramaView::rgbF32(map.rgb.data(), map.width, map.height));
  const lp::Projector projector(traced, frame.width, frame.height);
  // Seen: the sphere but the cone behind the ball and the camera's, 14.5 degrees each (together
  // 1 - cos(alpha) of the sphere), and the band round the hidden cone that the ball's last ring
  // of pixels, cut by its rim, would have shown.
  EXPECT_LT(projector.coverage(), std::cos(alpha));
  EXPECT_GT(projector.coverage(), 0.9);
  std::vector<float> peaks;
  const lp::Sh9 got = projector.project(view(traced), nullptr, &peaks);
  const lp::Sh9 orthographic = lp::Projector(far, frame.width, frame.height).project(view(far));
  std::printf("traced: %.2f%% of L00, orthographic: %.2f%%\n", 100 * worstOfL00(got, want),
              100 * worstOfL00(orthographic, want));
  EXPECT_LT(worstOfL00(got, want), 0.08);
  EXPECT_LT(worstOfL00(got, want), worstOfL00(orthographic, want));
  const lp::LightSplit split = lp::LightExtractor(projector).extract(view(traced), got, peaks, {});
  ASSERT_EQ(split.lights.size(), 1u);
  const double off =
      glm::degrees(std::acos(std::min(1.0, glm::dot(sun, glm::dvec3(split.lights[0].dir)))));
  std::printf("sun %.2f degrees off\n", off);
  EXPECT_LT(off, 1.0);

  // The command line: the circle and the camera's calibration.
  const std::string file = (tmp.path / "ball.exr").string();
  lp::saveImage(file, frame);
  char circleText[96];
  std::snprintf(circleText, sizeof circleText, "%.4f,%.4f,%.4f", circle.x, circle.y, circle.z);
  const auto r =
      lpt::runLiveprobe("coeffs " + file + " --layout mirrorball --circle " + circleText +
                        " --lens " + (tmp.path / "cam.yaml").string() + " --format json");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output.substr(r.output.find('{')));
  EXPECT_EQ(j["layout"], "mirrorball");
  EXPECT_NEAR(j["coverage"].get<double>(), projector.coverage(), 1e-4);  // the circle as text
  lp::Sh9 cli;
  for (int k = 0; k < 9; ++k)
    for (int c = 0; c < 3; ++c)
      cli.c[k][c] = j["coefficients"][std::string(lp::kShNames[k])][c].get<float>();
  EXPECT_LT(worstOfL00(cli, got), 1e-4) << r.output;

  // --circle auto with the calibration, on one image and replayed: a ball 2.5 radii away (its
  // silhouette 118 px, over the finder's tenth of the frame) that reflects 0.6 of the light, as
  // chrome does (a perfect mirror's rim reflects the very scene behind it and shows no edge). On
  // the lens's axis it shares its centre with the fisheye's image circle, a stronger circle, so
  // the ball is sought inside that circle. Its outline through the lens is a circle, found within
  // 0.25 px; a traced ball's radius is also its distance, so that costs more than an orthographic
  // ball's fifth of a pixel (0.4%): the coefficients within 1.5% of L00 of the true circle's
  // (measured 1.2%), against the 2.2% the true circle itself is off the map.
  double nearRim = 0;
  const lp::Image nearFrame = render(2.5, 0.6f, nearRim);
  const std::string nearFile = (tmp.path / "near.exr").string();
  lp::saveImage(nearFile, nearFrame);
  const glm::vec3 nearCircle(float(kb.cx + 0.5), float(kb.cy + 0.5), float(nearRim));
  lp::LayoutSpec nearSpec(lp::Layout::MirrorBall);
  nearSpec.circle = nearCircle;
  nearSpec.lens =
      lp::makeBallModel(lp::readLensCalibration((tmp.path / "cam.yaml").string()), nearCircle);
  const lp::Sh9 nearTruth =
      lp::Projector(nearSpec, nearFrame.width, nearFrame.height)
          .project(lp::PanoramaView::rgbF32(nearFrame.rgb.data(), nearFrame.width, nearFrame.height,
                                            nearSpec));
  const std::string ballArgs =
      nearFile + " --layout mirrorball --circle auto --lens " + (tmp.path / "cam.yaml").string();
  const auto found = lpt::runLiveprobe("coeffs " + ballArgs + " --format json");
  ASSERT_EQ(found.exitCode, 0) << found.output;
  const auto coefficientsOf = [](const nlohmann::json& j) {
    lp::Sh9 sh;
    for (int k = 0; k < 9; ++k)
      for (int c = 0; c < 3; ++c)
        sh.c[k][c] = j["coefficients"][std::string(lp::kShNames[k])][c].get<float>();
    return sh;
  };
  const lp::Sh9 fromFound =
      coefficientsOf(nlohmann::json::parse(found.output.substr(found.output.find('{'))));
  std::printf("traced, true circle %.2f,%.2f,%.2f; %s%.3f%% of L00 from the true circle's\n",
              nearCircle.x, nearCircle.y, nearCircle.z,
              found.output.substr(0, found.output.find('{')).c_str(),
              100 * worstOfL00(fromFound, nearTruth));
  EXPECT_LT(worstOfL00(fromFound, nearTruth), 0.015) << found.output;
  const auto replayed =
      lpt::runLiveprobe("replay " + ballArgs + " --headless --size 32x18 --frames 1 --coeffs-out " +
                        (tmp.path / "near.jsonl").string());
  ASSERT_EQ(replayed.exitCode, 0) << replayed.output;
  EXPECT_NE(replayed.output.find("mirror ball found at frame 1"), std::string::npos)
      << replayed.output;
  std::ifstream lines(tmp.path / "near.jsonl");
  std::string line;
  ASSERT_TRUE(std::getline(lines, line));
  EXPECT_LT(worstOfL00(coefficientsOf(nlohmann::json::parse(line)), nearTruth), 0.015) << line;
}

// ---- The command line ---------------------------------------------------------------------

TEST(Lens, CoeffsOfAFisheyeFrameFromTheCommandLine) {
  const lp::Image map = lp::loadImage(lpt::dataPath("equirect/pedestrian_overpass_1k.hdr"));
  FisheyeCamera camera;
  const glm::dmat3 world = tilt(35.0);
  const std::string frame = (camera.tmp.path / "sky.exr").string();
  const lp::Image image = fisheyeFrame(map, camera.kb, world);
  lp::saveImage(frame, image);
  const std::string lens = (camera.tmp.path / "sky.yaml").string();
  if (const char* dir = std::getenv("LIVEPROBE_LENS_PICTURES")) {  // scripts/lens-pictures
    fs::copy_file(frame, fs::path(dir) / "sky.exr", fs::copy_options::overwrite_existing);
    fs::copy_file(lens, fs::path(dir) / "sky.yaml", fs::copy_options::overwrite_existing);
    // The frame binned 2x2, as the camera's 640x480 mode: linear, and exposed at 0.5 to look at.
    lp::Image half(image.width / 2, image.height / 2);
    for (int y = 0; y < half.height; ++y)
      for (int x = 0; x < half.width; ++x)
        for (int c = 0; c < 3; ++c)
          half.pixel(x, y)[c] =
              0.25f * (image.pixel(2 * x, 2 * y)[c] + image.pixel(2 * x + 1, 2 * y)[c] +
                       image.pixel(2 * x, 2 * y + 1)[c] + image.pixel(2 * x + 1, 2 * y + 1)[c]);
    lp::saveImage((fs::path(dir) / "sky-640.exr").string(), half, true);
    for (float& v : half.rgb) v *= 0.5f;
    lp::saveImage((fs::path(dir) / "sky.png").string(), half);
  }
  // The mount said by --env-rotate: pitch turns about +y, so the same tilt about x is a roll.
  const auto r = lpt::runLiveprobe("coeffs " + frame + " --lens " + lens +
                                   " --env-rotate 0,0,35 --unseen ground=0.3 --format json");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output.substr(r.output.find('{')));
  EXPECT_EQ(j["layout"], "lens");
  EXPECT_NEAR(j["coverage"].get<double>(), 0.5, 0.002);
  EXPECT_EQ(j["unseen"], "ground=0.3");
  // The truth in the world frame: in the camera's frame, turned by the mount.
  const lp::Sh9 want = lp::rotateSh(truth(map, world, true, 0.3), glm::mat3(world));
  lp::Sh9 got;
  for (int k = 0; k < 9; ++k)
    for (int c = 0; c < 3; ++c)
      got.c[k][c] = j["coefficients"][std::string(lp::kShNames[k])][c].get<float>();
  EXPECT_LT(worstOfL00(got, want), 0.005) << r.output;
}

TEST(Lens, ALensThatDoesNotFitIsOneLine) {
  FisheyeCamera camera;
  const std::string lens = (camera.tmp.path / "sky.yaml").string();
  const std::string wide = (camera.tmp.path / "wide.png").string();
  ASSERT_TRUE(cv::imwrite(wide, cv::Mat(720, 1280, CV_8UC3, cv::Scalar(9, 9, 9))));
  lpt::expectOneLineError("coeffs " + wide + " --lens " + lens, lens, "another aspect");
  lpt::expectOneLineError("coeffs " + wide + " --layout lens", "--layout lens", "needs --lens");
  lpt::expectOneLineError("coeffs " + wide + " --layout angular --lens " + lens, "--lens",
                          "--layout lens or mirrorball only");
  lpt::expectOneLineError("coeffs " + wide + " --lens " + wide, wide, "not a lens calibration");
  lpt::expectOneLineError("coeffs " + wide + " --lens " + lens + " --unseen ground=2", "--unseen",
                          "from 0 to 1");
  // The same lens at half its size is the lens scaled, and said so.
  const std::string half = (camera.tmp.path / "half.png").string();
  ASSERT_TRUE(cv::imwrite(half, cv::Mat(480, 640, CV_8UC3, cv::Scalar(9, 9, 9))));
  const auto r = lpt::runLiveprobe("coeffs " + half + " --lens " + lens + " --format json");
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("scaled to this 640x480 frame"), std::string::npos) << r.output;
}

// ---- Calibration from chessboard photos ----------------------------------------------------
// Photos of a 9x6 board (30 mm squares) rendered through the tests' fisheye: each pixel the mean
// of 2x2 rays, each ray's direction solved from the lens (KannalaBrandt::direction) and met with
// the board's plane. The boards' centres reach 74 degrees off the axis, their corners 85.

struct BoardPose {
  double offAxisDeg, azimuthDeg, distance, tiltDeg;
};

void renderBoards(const KannalaBrandt& lens, const std::vector<BoardPose>& poses,
                  const lp::Chessboard& b, const fs::path& dir) {
  const int w = 1280, h = 960;
  std::vector<glm::vec3> rays;  // 2x2 per pixel, (0, 0, 0) where the lens sees nothing
  rays.reserve(std::size_t(w) * h * 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (const double a : {-0.25, 0.25})
        for (const double c : {-0.25, 0.25})
          rays.push_back(glm::vec3(lens.direction(x + c, y + a).value_or(glm::dvec3(0.0))));
  const double width = (b.cols + 1) * b.square, height = (b.rows + 1) * b.square;
  for (std::size_t n = 0; n < poses.size(); ++n) {
    const BoardPose& p = poses[n];
    const double t = glm::radians(p.offAxisDeg), f = glm::radians(p.azimuthDeg);
    const glm::dvec3 centre =
        p.distance * glm::dvec3(std::sin(t) * std::cos(f), std::sin(t) * std::sin(f), std::cos(t));
    // The board faces the camera, turned by the tilt about its horizontal axis.
    const glm::dvec3 facing = -glm::normalize(centre);
    glm::dvec3 ex = glm::normalize(glm::cross(glm::dvec3(0, 1, 0), facing));
    glm::dvec3 ey = glm::cross(facing, ex);
    const double tilt = glm::radians(p.tiltDeg);
    const glm::dvec3 normal = std::cos(tilt) * facing + std::sin(tilt) * ey;
    ey = glm::normalize(glm::cross(normal, ex));
    cv::Mat img(h, w, CV_8UC1);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        double sum = 0;
        for (int k = 0; k < 4; ++k) {
          const glm::dvec3 d(rays[(std::size_t(y) * w + std::size_t(x)) * 4 + std::size_t(k)]);
          double v = 0.0;  // outside the lens's circle: black
          if (d.z > 0) {
            v = 0.5;  // the room
            const double s = glm::dot(normal, centre) / glm::dot(normal, d);
            if (s > 0) {
              const glm::dvec3 q = s * d - centre;
              const double u = glm::dot(q, ex) + width / 2, vv = glm::dot(q, ey) + height / 2;
              if (u > -b.square && u < width + b.square && vv > -b.square &&
                  vv < height + b.square) {
                v = 1.0;  // the board's white margin
                if (u >= 0 && u < width && vv >= 0 && vv < height &&
                    (int(std::floor(u / b.square)) + int(std::floor(vv / b.square))) % 2 == 0)
                  v = 0.05;
              }
            }
          }
          sum += v;
        }
        img.at<std::uint8_t>(y, x) =
            std::uint8_t(std::lround(255 * lp::linearToSrgb(float(sum / 4))));
      }
    char name[32];
    std::snprintf(name, sizeof name, "board%02zu.png", n);
    ASSERT_TRUE(cv::imwrite((dir / name).string(), img));
  }
}

TEST(LensCalibration, AWideFisheyeFromChessboardPhotos) {
  const KannalaBrandt truth;
  lpt::TempDir tmp;
  const lp::Chessboard board{9, 6, 0.03};
  renderBoards(truth,
               {{0, 0, 0.35, 0},
                {25, 0, 0.35, 20},
                {25, 90, 0.35, -20},
                {25, 180, 0.35, 20},
                {25, 270, 0.35, -20},
                {45, 45, 0.4, 25},
                {45, 135, 0.4, -25},
                {45, 225, 0.4, 25},
                {45, 315, 0.4, -25},
                {65, 0, 0.5, 30},
                {65, 120, 0.5, 30},
                {65, 240, 0.5, 30},
                {74, 45, 0.65, 0},
                {74, 135, 0.65, 0},
                {74, 225, 0.65, 0},
                {74, 315, 0.65, 0}},
               board, tmp.path);
  if (const char* dir = std::getenv("LIVEPROBE_LENS_PICTURES")) {  // scripts/lens-pictures
    fs::create_directories(fs::path(dir) / "boards");
    for (const auto& e : fs::directory_iterator(tmp.path))
      fs::copy_file(e.path(), fs::path(dir) / "boards" / e.path().filename(),
                    fs::copy_options::overwrite_existing);
  }
  // The command line, as a user runs it, on the folder of photos.
  const std::string file = (tmp.path / "lens.yaml").string();
  const auto r = lpt::runLiveprobe("calibrate-lens " + tmp.path.string() +
                                   " --board 9x6 --square 0.03 --out " + file);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("16 of 16 photos show the 9x6 board"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the boards reached"), std::string::npos) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex(R"(RMS reprojection error ([0-9.]+) px)")))
      << r.output;
  EXPECT_LT(std::stod(m[1]), 0.5) << r.output;
  // Read back by liveprobe and by OpenCV itself.
  const lp::LensCalibration back = lp::readLensCalibration(file);
  EXPECT_EQ(back.model, lp::LensCalibration::Model::Fisheye);
  EXPECT_EQ(back.width, 1280);
  EXPECT_NEAR(back.K[0], truth.fx, 0.01 * truth.fx) << r.output;
  EXPECT_NEAR(back.K[4], truth.fy, 0.01 * truth.fy) << r.output;
  EXPECT_NEAR(back.K[2], truth.cx, 2.0) << r.output;
  EXPECT_NEAR(back.K[5], truth.cy, 2.0) << r.output;
  cv::FileStorage fs(file, cv::FileStorage::READ);
  cv::Mat K;
  fs["camera_matrix"] >> K;
  EXPECT_DOUBLE_EQ(K.at<double>(0, 0), back.K[0]);

  // A map through the recovered lens against the true one: a sky camera looking straight up at
  // quarry_01, its sun 80 degrees off the axis (docs/lenses.md gives pedestrian_overpass_1k's,
  // 87 degrees off, at the rim where the boards' corners do not reach).
  const lp::Image map = lp::loadImage(lpt::dataPath("equirect/quarry_01_1k.hdr"));
  const lp::Image frame = fisheyeFrame(map, truth, glm::dmat3(1.0));
  lp::LayoutSpec trueSpec(lp::Layout::Lens), fitSpec(lp::Layout::Lens);
  trueSpec.lens =
      lp::makeLensModel(lp::readLensCalibration(truth.write((tmp.path / "true.yaml").string())));
  fitSpec.lens = lp::makeLensModel(back);
  const auto project = [&](const lp::LayoutSpec& spec) {
    return lp::Projector(spec, frame.width, frame.height)
        .project(lp::PanoramaView::rgbF32(frame.rgb.data(), frame.width, frame.height, spec));
  };
  EXPECT_LT(worstOfL00(project(fitSpec), project(trueSpec)), 0.005);
}

TEST(LensCalibration, TooFewBoardsAreRefusedWithWhatWasFound) {
  const KannalaBrandt truth;
  lpt::TempDir tmp;
  const lp::Chessboard board{9, 6, 0.03};
  renderBoards(truth, {{0, 0, 0.35, 0}, {25, 0, 0.35, 20}}, board, tmp.path);
  ASSERT_TRUE(
      cv::imwrite((tmp.path / "wall.png").string(), cv::Mat(960, 1280, CV_8UC1, cv::Scalar(128))));
  lpt::expectOneLineError("calibrate-lens " + tmp.path.string() +
                              " --board 9x6 --square 0.03 --out " + (tmp.path / "l.yaml").string(),
                          "2 of 3 photos show the 9x6 board", "wall.png: no 9x6 board found");
  EXPECT_FALSE(fs::exists(tmp.path / "l.yaml"));
  lpt::expectOneLineError("calibrate-lens " + tmp.path.string() + " --square 0.03 --out l.yaml",
                          "--board", "required");
}

}  // namespace
