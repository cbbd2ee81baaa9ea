// Links liveprobe::sh and liveprobe::capture from an install. Computes the radiance coefficients
// of Debevec's Grace Cathedral probe and compares them with R&H 2001's table: the colour ratios
// of L00 within 1%, and each band's norm within 2.5% (the table's exposure is arbitrary, so the
// coefficients are compared after one common scale).
#include <liveprobe/capture/image.h>
#include <liveprobe/sh/error.h>
#include <liveprobe/sh/projector.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

namespace {
constexpr float kGrace[9][3] = {{.79f, .44f, .54f},    {.39f, .35f, .60f},    {-.34f, -.18f, -.27f},
                                {-.29f, -.06f, .01f},  {-.11f, -.05f, -.12f}, {-.26f, -.22f, -.47f},
                                {-.16f, -.09f, -.15f}, {.56f, .21f, .14f},    {.21f, -.05f, -.30f}};
}

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: grace GRACE_LATLONG.exr\n");
    return 2;
  }
  try {
    const lp::Image img = lp::loadImage(argv[1]);
    lp::ThreadPool pool(0);
    const lp::Sh9 L =
        lp::project(lp::PanoramaView::rgbF32(img.rgb.data(), img.width, img.height), &pool);
    double mean = 0;
    for (int ch = 0; ch < 3; ++ch) mean += L.c[0][ch] / kGrace[0][ch] / 3;
    int failures = 0;
    for (int k = 0; k < lp::kShCount; ++k)
      std::printf("%-5s %8.3f %8.3f %8.3f   paper %6.2f %6.2f %6.2f\n",
                  std::string(lp::kShNames[k]).c_str(), L.c[k].x / mean, L.c[k].y / mean,
                  L.c[k].z / mean, kGrace[k][0], kGrace[k][1], kGrace[k][2]);
    for (int ch = 0; ch < 3; ++ch) {
      const double ratio = L.c[0][ch] / kGrace[0][ch] / mean;
      if (std::abs(ratio - 1) > 0.01)
        ++failures, std::printf("L00 channel %d off by %.3f\n", ch, ratio - 1);
      for (int band = 0; band < 3; ++band) {
        double ours = 0, paper = 0;
        for (int k = 0; k < lp::kShCount; ++k)
          if (lp::shBand(k) == band)
            ours += std::pow(L.c[k][ch] / mean, 2), paper += std::pow(kGrace[k][ch], 2);
        const double off = std::sqrt(ours / paper) - 1;
        if (std::abs(off) > 0.025)
          ++failures, std::printf("band %d channel %d off by %.3f\n", band, ch, off);
      }
    }
    std::printf("grace: %s\n", failures ? "DIFFERS from R&H's table" : "matches R&H's table");
    return failures ? 1 : 0;
  } catch (const lp::Error& e) {
    std::fprintf(stderr, "grace: %s\n", e.what());
    return 1;
  }
}
