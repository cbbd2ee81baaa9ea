#include "liveprobe/capture/accuracy.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <glm/gtc/type_ptr.hpp>
#include <opencv2/imgproc.hpp>

#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/sh/brute.h"

namespace lp {

namespace {
double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

CompareResult compareIrradiance(const Image& img, const LayoutSpec& layout, int width, int height,
                                const BandWindow& window, unsigned threads,
                                const glm::mat3& orientation, const BruteProgress& progress,
                                const LightOptions* sun) {
  // The map through the frame path every command shares, timed: the SH side of the paper's
  // comparison, with the evaluation.
  Frame frame;
  frame.format = PanoramaFormat::RgbF32;
  frame.width = img.width, frame.height = img.height;
  frame.rgb = img.rgb;
  FrameProcessor processor(
      {layout, Photometry{}, orientation, 1, sun ? *sun : LightOptions{.maxLights = 0}});
  processor.fit(frame);  // the sample table is made once per size, as for a stream
  const auto t0 = std::chrono::steady_clock::now();
  const FrameLighting lit = processor.process(frame);
  return compareIrradiance(img, layout, lit, msSince(t0), sun != nullptr, width, height, window,
                           threads, orientation, progress);
}

CompareResult compareIrradiance(const Image& img, const LayoutSpec& layout,
                                const FrameLighting& lit, double projectMs, bool sun, int width,
                                int height, const BandWindow& window, unsigned threads,
                                const glm::mat3& orientation, const BruteProgress& progress) {
  const auto grid = equirectSamples(width, height);
  std::vector<glm::vec3> normals(grid.size());
  for (std::size_t i = 0; i < grid.size(); ++i) normals[i] = grid[i].dir;

  CompareResult r;
  r.width = width;
  r.height = height;
  r.ySh.resize(grid.size());
  r.yBrute.resize(grid.size());

  auto t0 = std::chrono::steady_clock::now();
  r.radiance = lit.whole;
  const auto m = irradianceMatrices(applyWindow(lit.whole, window));
  for (std::size_t i = 0; i < grid.size(); ++i)
    r.ySh[i] = luminance(evalIrradianceQuadratic(m, normals[i]));
  r.shMs = projectMs + msSince(t0);
  if (sun) {
    const Sh9 residual = applyWindow(lit.radiance, window);
    r.sun = true;
    r.lights = lit.lights;
    r.ySun.resize(grid.size());
    for (std::size_t i = 0; i < grid.size(); ++i)
      r.ySun[i] = luminance(evalIrradiance(residual, lit.lights, normals[i]));
  }
  // The oracle integrates the same pixels, each with its solid angle, turned to the world.
  auto samples = Projector(layout, img.width, img.height).samples();
  for (auto& s : samples) s.dir = orientation * s.dir;

  t0 = std::chrono::steady_clock::now();
  ThreadPool pool(threads);
  const auto brute =
      bruteIrradiance(img.rgb.data(), 3, samples.data(), samples.size(), normals, &pool, progress);
  r.bruteMs = msSince(t0);
  for (std::size_t i = 0; i < grid.size(); ++i) r.yBrute[i] = luminance(brute[i]);

  for (std::size_t i = 0; i < samples.size(); ++i)
    r.totalIntensity +=
        double(luminance(glm::make_vec3(img.rgb.data() + 3 * i))) * samples[i].solidAngle;

  double wsum = 0, esum = 0, errSum = 0, errMax = 0, shMin = INFINITY;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    const double w = grid[i].solidAngle, d = std::abs(double(r.ySh[i]) - r.yBrute[i]);
    wsum += w;
    esum += w * r.yBrute[i];
    errSum += w * d;
    errMax = std::max(errMax, d);
    shMin = std::min(shMin, double(r.ySh[i]));
  }
  r.meanIrradiance = esum / wsum;
  const double meanErr = errSum / wsum;
  r.meanFracTotal = meanErr / r.totalIntensity;
  r.maxFracTotal = errMax / r.totalIntensity;
  r.meanRelMean = meanErr / r.meanIrradiance;
  r.maxRelMean = errMax / r.meanIrradiance;
  r.minShOverMean = shMin / r.meanIrradiance;
  if (r.sun) {
    double sunSum = 0, sunMax = 0;
    for (std::size_t i = 0; i < grid.size(); ++i) {
      const double d = std::abs(double(r.ySun[i]) - r.yBrute[i]);
      sunSum += grid[i].solidAngle * d;
      sunMax = std::max(sunMax, d);
    }
    r.meanFracTotalSun = sunSum / wsum / r.totalIntensity;
    r.maxFracTotalSun = sunMax / r.totalIntensity;
  }
  return r;
}

void saveCompareFigure(const std::string& path, const CompareResult& r) {
  const int scale = std::max(1, 384 / r.width);
  const int pw = r.width * scale, ph = r.height * scale;
  const int label = 28, barW = 60, gap = 8;
  cv::Mat fig(ph + label, 3 * pw + 2 * gap + barW + 70, CV_8UC3, cv::Scalar(32, 32, 32));

  // Panels 1 and 2: the two irradiance maps, same exposure (brute-force maximum -> white).
  float peak = 1e-30f;
  for (float v : r.yBrute) peak = std::max(peak, v);
  auto drawMap = [&](const std::vector<float>& y, int x0) {
    cv::Mat small(r.height, r.width, CV_8UC3);
    for (int i = 0; i < r.height; ++i)
      for (int j = 0; j < r.width; ++j) {
        const auto v = std::uint8_t(std::lround(255 * linearToSrgb(y[i * r.width + j] / peak)));
        small.at<cv::Vec3b>(i, j) = {v, v, v};
      }
    cv::Mat big;
    cv::resize(small, big, {pw, ph}, 0, 0, cv::INTER_NEAREST);
    big.copyTo(fig(cv::Rect(x0, label, pw, ph)));
  };
  // With --sun the figure is of SH plus the lights (the "after" beside compare's "before").
  const std::vector<float>& ySh = r.sun ? r.ySun : r.ySh;
  drawMap(ySh, 0);
  drawMap(r.yBrute, pw + gap);

  // Panel 3: |E_sh - E| / total intensity, inferno colour map from 0 to the maximum error.
  const double emax = std::max(1e-12, r.sun ? r.maxFracTotalSun : r.maxFracTotal);
  cv::Mat err(r.height, r.width, CV_8UC1);
  for (int i = 0; i < r.height; ++i)
    for (int j = 0; j < r.width; ++j) {
      const double e =
          std::abs(double(ySh[i * r.width + j]) - r.yBrute[i * r.width + j]) / r.totalIntensity;
      err.at<std::uint8_t>(i, j) = std::uint8_t(std::lround(255 * std::min(1.0, e / emax)));
    }
  cv::Mat errBig, errColour;
  cv::resize(err, errBig, {pw, ph}, 0, 0, cv::INTER_NEAREST);
  cv::applyColorMap(errBig, errColour, cv::COLORMAP_INFERNO);
  errColour.copyTo(fig(cv::Rect(2 * (pw + gap), label, pw, ph)));

  // Colour bar with its range.
  const int bx = 3 * pw + 2 * gap + 10;
  cv::Mat ramp(ph, 1, CV_8UC1);
  for (int i = 0; i < ph; ++i)
    ramp.at<std::uint8_t>(i) = std::uint8_t(255 - 255 * i / std::max(1, ph - 1));
  cv::Mat rampW, rampC;
  cv::resize(ramp, rampW, {16, ph}, 0, 0, cv::INTER_NEAREST);
  cv::applyColorMap(rampW, rampC, cv::COLORMAP_INFERNO);
  rampC.copyTo(fig(cv::Rect(bx, label, 16, ph)));
  char text[64];
  std::snprintf(text, sizeof text, "%.2f%%", 100 * emax);
  const auto white = cv::Scalar(235, 235, 235);
  cv::putText(fig, text, {bx + 20, label + 12}, cv::FONT_HERSHEY_SIMPLEX, 0.4, white);
  cv::putText(fig, "0%", {bx + 20, label + ph - 2}, cv::FONT_HERSHEY_SIMPLEX, 0.4, white);
  cv::putText(fig, r.sun ? "SH + lights" : "SH (9 coefficients)", {4, 19}, cv::FONT_HERSHEY_SIMPLEX,
              0.5, white);
  cv::putText(fig, "brute force", {pw + gap + 4, 19}, cv::FONT_HERSHEY_SIMPLEX, 0.5, white);
  cv::putText(fig, "|error| / total intensity", {2 * (pw + gap) + 4, 19}, cv::FONT_HERSHEY_SIMPLEX,
              0.5, white);
  saveImage8(path, fig.cols, fig.rows, 3, fig.ptr<std::uint8_t>());
}

}  // namespace lp
