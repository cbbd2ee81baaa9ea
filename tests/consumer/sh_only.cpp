// Links liveprobe::sh only. A constant environment of radiance c has L00 = 4 pi Y00 c and every
// other coefficient zero, and irradiance pi c for every normal (analytic), in every layout.
#include <liveprobe/sh/projector.h>
#include <liveprobe/sh/sh.h>

#include <cmath>
#include <cstdio>
#include <vector>

int main() {
  const float c = 0.75f;
  int failures = 0;
  lp::ThreadPool pool(2);
  for (lp::Layout layout : {lp::Layout::Equirect, lp::Layout::Angular, lp::Layout::DualFisheye}) {
    const int h = 128, w = layout == lp::Layout::Angular ? 128 : 256;
    const std::vector<float> rgb(std::size_t(w) * h * 3, c);
    const lp::Sh9 L = lp::project(lp::PanoramaView::rgbF32(rgb.data(), w, h, layout), &pool);
    const double l00 = 4 * lp::kPi * lp::kY00 * c;
    const glm::vec3 e = lp::evalIrradiance(L, glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f)));
    bool ok = std::abs(L.c[0].x - l00) < 1e-3 * l00 && std::abs(e.y - lp::kPi * c) < 1e-3 * c;
    for (int k = 1; k < lp::kShCount; ++k) ok = ok && std::abs(L.c[k].z) < 1e-3 * l00;
    std::printf("%-8s L00 %.6f (expected %.6f), E %.6f (expected %.6f): %s\n",
                std::string(lp::layoutName(layout)).c_str(), L.c[0].x, l00, e.y, lp::kPi * c,
                ok ? "ok" : "WRONG");
    failures += !ok;
  }
  return failures ? 1 : 0;
}
