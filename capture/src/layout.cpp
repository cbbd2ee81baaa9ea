#include "capture/layout.h"

#include <cmath>
#include <numbers>

#include "capture/error.h"

namespace lp {

std::string_view layoutName(Layout layout) {
  switch (layout) {
    case Layout::Equirect: return "equirect";
    case Layout::Angular: return "angular";
  }
  return "?";
}

Layout parseLayout(std::string_view name) {
  if (name == "equirect" || name == "latlong") return Layout::Equirect;
  if (name == "angular" || name == "probe") return Layout::Angular;
  throw Error("--layout " + std::string(name) + ": unknown layout (expected equirect or angular)");
}

std::string layoutMismatch(Layout layout, int width, int height) {
  if (width <= 0 || height <= 0) return "empty frame";
  if (layout == Layout::Angular && width != height)
    return "an angular map must be square, this frame is " + std::to_string(width) + "x" +
           std::to_string(height);
  if (layout == Layout::Angular && width < 2) return "an angular map needs at least 2x2 pixels";
  return {};
}

std::vector<SphereSample> equirectSamples(int width, int height) {
  std::vector<SphereSample> out(std::size_t(width) * height);
  const double pi = std::numbers::pi;
  for (int i = 0; i < height; ++i) {
    const double t = pi * (i + 0.5) / height;
    const double t0 = pi * i / height, t1 = pi * (i + 1) / height;
    const float dw = float((2.0 * pi / width) * (std::cos(t0) - std::cos(t1)));
    const double st = std::sin(t), ct = std::cos(t);
    for (int j = 0; j < width; ++j) {
      const double p = 2.0 * pi * (j + 0.5) / width;
      out[std::size_t(i) * width + j] = {
          glm::vec3(float(st * std::cos(p)), float(st * std::sin(p)), float(ct)), dw};
    }
  }
  return out;
}

namespace {

std::vector<SphereSample> angularSamples(int w) {
  const double pi = std::numbers::pi;
  const double half = w / 2.0;
  std::vector<SphereSample> out(std::size_t(w) * w);
  constexpr int kSub = 8;
  double total = 0.0;
  for (int i = 0; i < w; ++i) {
    for (int j = 0; j < w; ++j) {
      const double u = (j + 0.5 - half) / half, v = (half - i - 0.5) / half;
      const double r = std::sqrt(u * u + v * v);
      // Solid angle: integral over the pixel of pi sin(pi r)/r du dv, inside the disc only.
      double dw = 0.0;
      for (int a = 0; a < kSub; ++a) {
        for (int b = 0; b < kSub; ++b) {
          const double su = (j + (b + 0.5) / kSub - half) / half;
          const double sv = (half - i - (a + 0.5) / kSub) / half;
          const double sr = std::sqrt(su * su + sv * sv);
          if (sr >= 1.0) continue;
          dw += sr < 1e-12 ? pi * pi : pi * std::sin(pi * sr) / sr;
        }
      }
      dw *= (2.0 / w) * (2.0 / w) / (kSub * kSub);
      SphereSample& s = out[std::size_t(i) * w + j];
      if (dw == 0.0) {
        s = {glm::vec3(0.0f), 0.0f};
        continue;
      }
      // Direction at the pixel centre (clamped to the disc for edge pixels whose centre is out).
      const double t = pi * std::min(r, 1.0), p = std::atan2(v, u);
      const glm::vec3 local(float(std::sin(t) * std::cos(p)), float(std::sin(t) * std::sin(p)),
                            float(std::cos(t)));
      s = {angularToWorld(local), float(dw)};
      total += dw;
    }
  }
  const double fix = 4.0 * pi / total;
  for (auto& s : out) s.solidAngle = float(s.solidAngle * fix);
  return out;
}

}  // namespace

std::vector<SphereSample> layoutSamples(Layout layout, int width, int height) {
  if (auto why = layoutMismatch(layout, width, height); !why.empty())
    throw Error(std::string(layoutName(layout)) + " layout: " + why);
  switch (layout) {
    case Layout::Equirect: return equirectSamples(width, height);
    case Layout::Angular: return angularSamples(width);
  }
  return {};
}

}  // namespace lp

namespace lp {

Projector::Projector(Layout layout, int width, int height)
    : layout_(layout), width_(width), height_(height),
      samples_(layoutSamples(layout, width, height)) {
  if (layout == Layout::Equirect) equirect_.emplace(width, height);
}

Sh9 Projector::project(const float* rgb, std::size_t rowStride) const {
  if (rowStride == 0) rowStride = std::size_t(width_) * 3;
  if (equirect_) return equirect_->project(rgb, rowStride);
  if (rowStride == std::size_t(width_) * 3)
    return projectSamples(rgb, 3, samples_.data(), samples_.size());
  Sh9 sum;
  for (int i = 0; i < height_; ++i)
    sum += projectSamples(rgb + i * rowStride, 3, samples_.data() + std::size_t(i) * width_,
                          std::size_t(width_));
  return sum;
}

}  // namespace lp
