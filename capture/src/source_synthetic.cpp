#include <cmath>
#include <glm/glm.hpp>

#include "liveprobe/capture/open_source.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/sh/sh.h"
#include "sources.h"

namespace lp {

glm::vec3 syntheticSunDirection(double t) {
  // Circles the sky every 20 s, bobbing in elevation every 10 s.
  const double sunAz = 2 * kPi * t / 20.0,
               sunEl = glm::radians(30.0 + 20.0 * std::sin(2 * kPi * t / 10.0));
  return glm::vec3(std::cos(sunEl) * std::cos(sunAz), std::cos(sunEl) * std::sin(sunAz),
                   std::sin(sunEl));
}

void renderSyntheticSky(int width, int height, double t, std::vector<float>& rgb) {
  constexpr double pi = kPi;
  rgb.resize(std::size_t(width) * height * 3);
  const glm::dvec3 sun(syntheticSunDirection(t));
  // Two coloured area lights near the horizon, turning the other way at other speeds.
  struct AreaLight {
    double az, el, halfWidth, halfHeight;
    glm::dvec3 colour;
  };
  const AreaLight lights[2] = {{-2 * pi * t / 7.0 + 1.0,
                                glm::radians(8.0),
                                glm::radians(18.0),
                                glm::radians(9.0),
                                {3.0, 0.4, 0.3}},
                               {-2 * pi * t / 13.0 + 3.5,
                                glm::radians(15.0),
                                glm::radians(10.0),
                                glm::radians(12.0),
                                {0.3, 1.6, 2.4}}};
  for (int i = 0; i < height; ++i) {
    const double th = pi * (i + 0.5) / height, z = std::cos(th), el = pi / 2 - th;
    for (int j = 0; j < width; ++j) {
      const double p = 2 * pi * (j + 0.5) / width;
      const glm::dvec3 d(std::sin(th) * std::cos(p), std::sin(th) * std::sin(p), z);
      glm::dvec3 L;
      if (z >= 0) {  // sky: horizon haze to zenith blue
        const double k = std::pow(z, 0.4);
        L = glm::mix(glm::dvec3(0.85, 0.85, 0.9), glm::dvec3(0.15, 0.3, 0.75), k);
      } else {  // ground: warm grey, darker downwards
        L = glm::dvec3(0.22, 0.18, 0.14) * (0.6 + 0.4 * (1 + z));
      }
      const double cosSun = glm::dot(d, sun);
      // The sun: a bright core of about 1 degree (40% of the map's power, as a clear day's sun)
      // in a soft ~5 degree aureole.
      L += glm::dvec3(1600.0, 1500.0, 1350.0) * std::exp((cosSun - 1.0) / 0.0004);
      L += glm::dvec3(3.0, 2.6, 2.0) * std::exp((cosSun - 1.0) / 0.004);
      L += glm::dvec3(0.4, 0.3, 0.2) * std::pow(std::max(0.0, cosSun), 8.0);  // glow
      for (const auto& a : lights) {
        double dAz = std::remainder(p - a.az, 2 * pi);
        if (std::abs(dAz) < a.halfWidth && std::abs(el - a.el) < a.halfHeight) L += a.colour;
      }
      float* px = rgb.data() + (std::size_t(i) * width + j) * 3;
      px[0] = float(L.x), px[1] = float(L.y), px[2] = float(L.z);
    }
  }
}

namespace {

class SyntheticSource final : public FrameSource {
 public:
  SyntheticSource(int w, int h, double fps) : w_(w), h_(h), fps_(fps) {}
  bool next(Frame& f) override {
    f.sequence = n_;
    f.timestamp = double(n_) / fps_;
    f.width = w_, f.height = h_;
    f.format = PanoramaFormat::RgbF32;
    f.bgr8.clear();
    renderSyntheticSky(w_, h_, f.timestamp, f.rgb);
    ++n_;
    return true;
  }
  bool rewind() override {
    n_ = 0;
    return true;
  }
  std::string describe() const override {
    return "synthetic sky " + std::to_string(w_) + "x" + std::to_string(h_) + " @ " +
           formatFps(fps_);
  }
  double fps() const override { return fps_; }

 private:
  int w_, h_;
  double fps_;
  std::uint64_t n_ = 0;
};

}  // namespace

std::unique_ptr<FrameSource> openSynthetic(int width, int height, double fps) {
  return std::make_unique<SyntheticSource>(width, height, fps);
}

}  // namespace lp
