#include "liveprobe/sh/layout.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>

#include "liveprobe/sh/axes.h"
#include "liveprobe/sh/error.h"

namespace lp {

std::string_view layoutName(Layout layout) {
  switch (layout) {
    case Layout::Equirect:
      return "equirect";
    case Layout::Angular:
      return "angular";
    case Layout::MirrorBall:
      return "mirrorball";
    case Layout::Cube:
      return "cube";
    case Layout::DualFisheye:
      return "fisheye";
    case Layout::Lens:
      return "lens";
  }
  return "?";
}

Layout parseLayout(std::string_view name) {
  if (name == "equirect" || name == "latlong") return Layout::Equirect;
  if (name == "angular" || name == "probe") return Layout::Angular;
  if (name == "mirrorball" || name == "ball") return Layout::MirrorBall;
  if (name == "cube" || name == "cross") return Layout::Cube;
  if (name == "fisheye" || name == "dual-fisheye") return Layout::DualFisheye;
  if (name == "lens") return Layout::Lens;
  throw Error("unknown layout " + std::string(name) +
              " (expected equirect, angular, mirrorball, cube, fisheye or lens)");
}

std::string unseenName(const UnseenRule& rule) {
  switch (rule.fill) {
    case UnseenRule::Fill::Ground: {
      char albedo[32];
      std::snprintf(albedo, sizeof albedo, "%g", double(rule.albedo));
      return std::string("ground=") + albedo;
    }
    case UnseenRule::Fill::Mean:
      return "mean";
    case UnseenRule::Fill::Black:
      return "black";
  }
  return "?";
}

UnseenRule parseUnseen(std::string_view text) {
  UnseenRule rule;
  if (text == "mean") {
    rule.fill = UnseenRule::Fill::Mean;
  } else if (text == "black") {
    rule.fill = UnseenRule::Fill::Black;
  } else if (text == "ground") {
    rule.fill = UnseenRule::Fill::Ground;
  } else if (text.starts_with("ground=")) {
    const std::string value(text.substr(7));
    char* end = nullptr;
    const double albedo = std::strtod(value.c_str(), &end);
    if (value.empty() || *end != '\0' || !(albedo >= 0.0 && albedo <= 1.0))
      throw Error("unseen " + std::string(text) +
                  ": the ground's albedo must be a number from 0 to 1");
    rule.albedo = float(albedo);
  } else {
    throw Error("unknown unseen rule " + std::string(text) +
                " (expected ground, ground=ALBEDO, mean or black)");
  }
  return rule;
}

std::string layoutMismatch(const LayoutSpec& spec, int width, int height) {
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  if (width <= 0 || height <= 0) return "empty frame";
  switch (spec.layout) {
    case Layout::Equirect:
      return {};
    case Layout::Angular:
      if (width != height) return "an angular map must be square, this frame is " + size;
      if (width < 2) return "an angular map needs at least 2x2 pixels";
      return {};
    case Layout::MirrorBall: {
      const auto c = spec.circle;
      if (!(c.z > 1.0f)) return "a mirror ball needs its circle (centre and radius in pixels)";
      if (c.x - c.z < -0.5f || c.y - c.z < -0.5f || c.x + c.z > width + 0.5f ||
          c.y + c.z > height + 0.5f)
        return "the mirror ball's circle does not fit in the " + size + " frame";
      return spec.lens ? spec.lens->mismatch(width, height) : std::string();
    }
    case Layout::Cube:
      if ((width * 3 == height * 4 && width % 4 == 0) ||
          (width * 4 == height * 3 && width % 3 == 0))
        return {};
      return "a cube cross must be 4:3 (horizontal) or 3:4 (vertical) with square faces, this "
             "frame is " +
             size;
    case Layout::DualFisheye:
      if (width != 2 * height) return "a dual fisheye frame must be 2:1, this frame is " + size;
      if (!(spec.fisheyeFovDeg > 180.0f && spec.fisheyeFovDeg <= 270.0f))
        return "the fisheye field of view must be in (180, 270] degrees";
      return {};
    case Layout::Lens:
      if (!spec.lens) return "the lens layout needs the camera's lens calibration";
      return spec.lens->mismatch(width, height);
  }
  return {};
}

std::vector<SphereSample> equirectSamples(int width, int height) {
  std::vector<SphereSample> out(std::size_t(width) * height);
  for (int i = 0; i < height; ++i) {
    const double t = kPi * (i + 0.5) / height;
    const double t0 = kPi * i / height, t1 = kPi * (i + 1) / height;
    const float dw = float((2.0 * kPi / width) * (std::cos(t0) - std::cos(t1)));
    const double st = std::sin(t), ct = std::cos(t);
    for (int j = 0; j < width; ++j) {
      const double p = 2.0 * kPi * (j + 0.5) / width;
      out[std::size_t(i) * width + j] = {
          glm::vec3(float(st * std::cos(p)), float(st * std::sin(p)), float(ct)), dw};
    }
  }
  return out;
}

namespace {

// ---- Cube faces (OpenGL convention) ----------------------------------------------------------
enum Face { PX, NX, PY, NY, PZ, NZ };

glm::vec3 cubeDirGl(int face, double s, double t) {
  const double sc = 2 * s - 1, tc = 2 * t - 1;
  switch (face) {
    case PX:
      return glm::vec3(1, -tc, -sc);
    case NX:
      return glm::vec3(-1, -tc, sc);
    case PY:
      return glm::vec3(sc, 1, tc);
    case NY:
      return glm::vec3(sc, -1, -tc);
    case PZ:
      return glm::vec3(sc, -tc, 1);
    default:
      return glm::vec3(-sc, -tc, -1);
  }
}

// Which face and (s, t) a GL direction hits.
void cubeFaceOf(glm::vec3 r, int* face, double* s, double* t) {
  const glm::vec3 a = glm::abs(r);
  double sc, tc, ma;
  if (a.x >= a.y && a.x >= a.z) {
    ma = a.x;
    if (r.x > 0)
      *face = PX, sc = -r.z, tc = -r.y;
    else
      *face = NX, sc = r.z, tc = -r.y;
  } else if (a.y >= a.z) {
    ma = a.y;
    if (r.y > 0)
      *face = PY, sc = r.x, tc = r.z;
    else
      *face = NY, sc = r.x, tc = -r.z;
  } else {
    ma = a.z;
    if (r.z > 0)
      *face = PZ, sc = r.x, tc = -r.y;
    else
      *face = NZ, sc = -r.x, tc = -r.y;
  }
  *s = (sc / ma + 1) / 2;
  *t = (tc / ma + 1) / 2;
}

struct CubeCell {
  int col, row;
  bool rotated;
};

// Cell of each face in the cross; vertical crosses hold -Z rotated by 180 degrees.
CubeCell cubeCell(int face, bool vertical) {
  static const CubeCell h[6] = {{2, 1, false}, {0, 1, false}, {1, 0, false},
                                {1, 2, false}, {1, 1, false}, {3, 1, false}};
  static const CubeCell v[6] = {{2, 1, false}, {0, 1, false}, {1, 0, false},
                                {1, 2, false}, {1, 1, false}, {1, 3, true}};
  return vertical ? v[face] : h[face];
}

double cubeAreaF(double a, double b) { return std::atan2(a * b, std::sqrt(a * a + b * b + 1)); }

std::vector<SphereSample> cubeSamples(int width, int height) {
  const bool vertical = width * 4 == height * 3;
  const int n = vertical ? width / 3 : width / 4;
  std::vector<SphereSample> out(std::size_t(width) * height, SphereSample{glm::vec3(0), 0.0f});
  for (int face = 0; face < 6; ++face) {
    const CubeCell cell = cubeCell(face, vertical);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        // (j, i) are the face's own texel indices; the cross stores rotated faces flipped.
        const int x = cell.col * n + (cell.rotated ? n - 1 - j : j);
        const int y = cell.row * n + (cell.rotated ? n - 1 - i : i);
        const double a0 = 2.0 * j / n - 1, a1 = 2.0 * (j + 1) / n - 1;
        const double b0 = 2.0 * i / n - 1, b1 = 2.0 * (i + 1) / n - 1;
        const double dw =
            cubeAreaF(a1, b1) - cubeAreaF(a0, b1) - cubeAreaF(a1, b0) + cubeAreaF(a0, b0);
        const glm::vec3 g = glm::normalize(cubeDirGl(face, (j + 0.5) / n, (i + 0.5) / n));
        out[std::size_t(y) * width + x] = {axes::worldFromGl(g), float(dw)};
      }
  }
  return out;
}

// ---- Layouts given by a direction map and a solid-angle density ---------------------------
// dir(x, y): world direction at continuous pixel coordinates, or nullopt outside the layout;
// density(x, y): steradians per unit pixel area there. Each pixel's solid angle is the mean of
// the density over sub-samples (8x8 where the layout's edge crosses the pixel, 2x2 inside);
// the total is then scaled to exactly 4 pi. offLayout(x, y), where given: true where the pixel
// centred at (x, y) lies wholly off the layout (a disc's frame around it), which then takes no
// sub-samples.
using DirFn = std::function<std::optional<glm::dvec3>(double, double)>;
using DensityFn = std::function<double(double, double)>;
using OffLayoutFn = std::function<bool(double, double)>;

std::vector<SphereSample> integratedSamples(int width, int height, const DirFn& dir,
                                            const DensityFn& density,
                                            const OffLayoutFn& offLayout = nullptr) {
  std::vector<SphereSample> out(std::size_t(width) * height);
  double total = 0.0;
  for (int i = 0; i < height; ++i)
    for (int j = 0; j < width; ++j) {
      if (offLayout && offLayout(j + 0.5, i + 0.5)) {
        out[std::size_t(i) * width + j] = {glm::vec3(0.0f), 0.0f};
        continue;
      }
      // Pixels wholly inside the layout have a smooth density: 2x2 sub-samples are plenty. Pixels
      // the layout's edge crosses get 8x8.
      const bool inside = density(j, i) > 0 && density(j + 1, i) > 0 && density(j, i + 1) > 0 &&
                          density(j + 1, i + 1) > 0;
      const int sub = inside ? 2 : 8;
      double dw = 0.0;
      glm::dvec3 sum(0.0);
      for (int a = 0; a < sub; ++a)
        for (int b = 0; b < sub; ++b) {
          const double x = j + (b + 0.5) / sub, y = i + (a + 0.5) / sub;
          const double d = density(x, y);
          if (d <= 0.0) continue;
          dw += d;
          if (!inside)
            if (auto w = dir(x, y)) sum += d * *w;
        }
      dw /= sub * sub;
      SphereSample& s = out[std::size_t(i) * width + j];
      if (dw <= 0.0) {
        s = {glm::vec3(0.0f), 0.0f};
        continue;
      }
      auto centre = dir(j + 0.5, i + 0.5);
      const glm::dvec3 d = centre ? *centre : sum;  // edge pixels: the weighted mean direction
      s = {glm::vec3(glm::normalize(d)), float(dw)};
      total += dw;
    }
  const double fix = 4.0 * kPi / total;
  for (auto& s : out) s.solidAngle = float(s.solidAngle * fix);
  return out;
}

// Direction from a polar angle t and azimuth p in a lens-like local frame
// (right, up, forward) = (sin t cos p, sin t sin p, cos t).
glm::dvec3 localDir(double t, double p) {
  return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

struct Disc {
  double cx, cy, r;
  // Normalised radius and azimuth of pixel point (x, y); azimuth counter-clockwise from right.
  std::pair<double, double> polar(double x, double y) const {
    const double u = (x - cx) / r, v = (cy - y) / r;
    return {std::sqrt(u * u + v * v), std::atan2(v, u)};
  }
  // The normalised radius alone (a density asks it of 64 points of each pixel on the disc's edge
  // and off it: no azimuth).
  double radius(double x, double y) const {
    const double u = (x - cx) / r, v = (cy - y) / r;
    return std::sqrt(u * u + v * v);
  }
  // Whether the pixel centred at (x, y) lies wholly off the disc (its corners are within 0.71 px).
  bool off(double x, double y) const { return std::hypot(x - cx, y - cy) > r + 0.75; }
};

std::vector<SphereSample> angularSamples(int w) {
  const Disc disc{w / 2.0, w / 2.0, w / 2.0};
  auto dir = [&](double x, double y) -> std::optional<glm::dvec3> {
    auto [r, p] = disc.polar(x, y);
    if (r > 1.0) return std::nullopt;
    const glm::dvec3 l = localDir(kPi * r, p);
    return glm::dvec3(-l.z, -l.x, l.y);  // angularToWorld
  };
  auto density = [&](double x, double y) {
    const double r = disc.radius(x, y);
    if (r >= 1.0) return 0.0;
    const double scale = 1.0 / (disc.r * disc.r);  // (du dv) per pixel area
    return scale * (r < 1e-12 ? kPi * kPi : kPi * std::sin(kPi * r) / r);
  };
  return integratedSamples(w, w, dir, density, [&](double x, double y) { return disc.off(x, y); });
}

std::vector<SphereSample> mirrorBallSamples(const LayoutSpec& spec, int width, int height) {
  const Disc disc{spec.circle.x, spec.circle.y, spec.circle.z};
  auto dir = [&](double x, double y) -> std::optional<glm::dvec3> {
    auto [r, p] = disc.polar(x, y);
    if (r > 1.0) return std::nullopt;
    const glm::dvec3 l = localDir(2.0 * std::asin(r), p);
    return glm::dvec3(-l.z, -l.x, l.y);
  };
  auto density = [&](double x, double y) {
    return disc.radius(x, y) < 1.0 ? 4.0 / (disc.r * disc.r) : 0.0;
  };
  return integratedSamples(width, height, dir, density,
                           [&](double x, double y) { return disc.off(x, y); });
}

struct Fisheye {
  double halfFov, radius, cy, cxFront, cxBack;
  double k() const { return halfFov / radius; }  // radians per pixel
  // Linear feather across the overlap band: 1 at t <= pi - halfFov, 0 at t = halfFov.
  double feather(double t) const {
    const double lo = kPi - halfFov;
    if (t <= lo) return 1.0;
    if (t >= halfFov) return 0.0;
    return (halfFov - t) / (halfFov - lo);
  }
};

std::vector<SphereSample> fisheyeSamples(const LayoutSpec& spec, int width, int height) {
  const Fisheye f{glm::radians(double(spec.fisheyeFovDeg)) / 2, height / 2.0, height / 2.0,
                  width / 4.0, 3.0 * width / 4.0};
  // Which lens a pixel belongs to, and its (t, p) there.
  auto lens = [&](double x, double y, bool* front, double* t, double* p) {
    *front = x < width / 2.0;
    const Disc d{*front ? f.cxFront : f.cxBack, f.cy, f.radius};
    auto [r, az] = d.polar(x, y);
    *t = r * f.halfFov;
    *p = az;
    return r <= 1.0;
  };
  auto dir = [&](double x, double y) -> std::optional<glm::dvec3> {
    bool front;
    double t, p;
    if (!lens(x, y, &front, &t, &p)) return std::nullopt;
    const glm::dvec3 l = localDir(t, p);  // (right, up, forward)
    return front ? glm::dvec3(-l.z, -l.x, l.y) : glm::dvec3(l.z, l.x, l.y);
  };
  auto density = [&](double x, double y) {
    bool front;
    double t, p;
    if (!lens(x, y, &front, &t, &p)) return 0.0;
    const double k = f.k();
    return k * k * (t < 1e-12 ? 1.0 : std::sin(t) / t) * f.feather(t);
  };
  return integratedSamples(width, height, dir, density);
}

}  // namespace

namespace {
/// The frame's pixels are the lens's to map: a calibrated camera, or a mirror ball traced
/// through one.
bool throughLens(const LayoutSpec& spec) {
  return spec.lens && (spec.layout == Layout::Lens || spec.layout == Layout::MirrorBall);
}
}  // namespace

std::vector<SphereSample> layoutSamples(const LayoutSpec& spec, int width, int height) {
  if (auto why = layoutMismatch(spec, width, height); !why.empty())
    throw Error(std::string(layoutName(spec.layout)) + " layout: " + why);
  switch (spec.layout) {
    case Layout::Equirect:
      return equirectSamples(width, height);
    case Layout::Angular:
      return angularSamples(width);
    case Layout::MirrorBall:
      return throughLens(spec) ? spec.lens->samples(width, height)
                               : mirrorBallSamples(spec, width, height);
    case Layout::Cube:
      return cubeSamples(width, height);
    case Layout::DualFisheye:
      return fisheyeSamples(spec, width, height);
    case Layout::Lens:
      return spec.lens->samples(width, height);
  }
  return {};
}

glm::vec3 cubeFaceDirection(int face, double s, double t) {
  return axes::worldFromGl(cubeDirGl(face, s, t));
}

std::optional<glm::vec2> layoutPixel(const LayoutSpec& spec, int width, int height, glm::vec3 dir) {
  const glm::dvec3 d = glm::normalize(glm::dvec3(dir));
  if (throughLens(spec)) {
    glm::vec2 at;
    const glm::vec3 unit(d);
    spec.lens->pixels(width, height, &unit, 1, &at);
    if (!std::isfinite(at.x) || !std::isfinite(at.y)) return std::nullopt;
    return at;
  }
  auto onDisc = [](double cx, double cy, double radius, double r, double p) {
    return glm::vec2(float(cx + radius * r * std::cos(p)), float(cy - radius * r * std::sin(p)));
  };
  switch (spec.layout) {
    case Layout::Equirect: {
      double p = std::atan2(d.y, d.x);
      if (p < 0) p += 2 * kPi;
      return glm::vec2(float(p / (2 * kPi) * width),
                       float(std::acos(std::clamp(d.z, -1.0, 1.0)) / kPi * height));
    }
    case Layout::Angular:
    case Layout::MirrorBall: {
      const glm::dvec3 l(-d.y, d.z, -d.x);  // worldToAngular
      const double t = std::acos(std::clamp(l.z, -1.0, 1.0)), p = std::atan2(l.y, l.x);
      if (spec.layout == Layout::Angular)
        return onDisc(width / 2.0, width / 2.0, width / 2.0, t / kPi, p);
      return onDisc(spec.circle.x, spec.circle.y, spec.circle.z, std::sin(t / 2), p);
    }
    case Layout::Cube: {
      int face;
      double s, t;
      cubeFaceOf(axes::glFromWorld(glm::vec3(d)), &face, &s, &t);
      const bool vertical = width * 4 == height * 3;
      const int n = vertical ? width / 3 : width / 4;
      const CubeCell c = cubeCell(face, vertical);
      if (c.rotated) s = 1 - s, t = 1 - t;
      return glm::vec2(float((c.col + s) * n), float((c.row + t) * n));
    }
    case Layout::DualFisheye: {
      const double halfFov = glm::radians(double(spec.fisheyeFovDeg)) / 2, radius = height / 2.0;
      const bool front = d.x <= 0;
      // Local (right, up, forward) of the chosen lens.
      const glm::dvec3 l = front ? glm::dvec3(-d.y, d.z, -d.x) : glm::dvec3(d.y, d.z, d.x);
      const double t = std::acos(std::clamp(l.z, -1.0, 1.0)), p = std::atan2(l.y, l.x);
      if (t > halfFov) return std::nullopt;
      return onDisc(front ? width / 4.0 : 3.0 * width / 4.0, height / 2.0, radius, t / halfFov, p);
    }
    case Layout::Lens:
      return std::nullopt;  // without its lens (with one, above)
  }
  return std::nullopt;
}

void layoutPixels(const LayoutSpec& spec, int width, int height, const glm::vec3* dirs,
                  std::size_t count, glm::vec2* out) {
  if (throughLens(spec)) {
    spec.lens->pixels(width, height, dirs, count, out);
    return;
  }
  for (std::size_t i = 0; i < count; ++i)
    out[i] = layoutPixel(spec, width, height, dirs[i]).value_or(glm::vec2(NAN));
}

}  // namespace lp
