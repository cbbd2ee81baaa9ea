// Published numbers: the Grace Cathedral coefficients of R&H 2001 (sh-notes.md), from the real
// Debevec probe in lat-long form. The file's exposure and axes differ from the paper's, so we
// compare what both leave unchanged: colour ratios of L00 and per-band norms.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "disc_equirect.h"
#include "liveprobe/capture/accuracy.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/sh/layout.h"
#include "liveprobe/sh/projector.h"
#include "test_util.h"

namespace {

// R&H Table: L00, L1-1, L10, L11, L2-2, L2-1, L20, L21, L22 (RGB).
constexpr float kGrace[9][3] = {{.79f, .44f, .54f},    {.39f, .35f, .60f},    {-.34f, -.18f, -.27f},
                                {-.29f, -.06f, .01f},  {-.11f, -.05f, -.12f}, {-.26f, -.22f, -.47f},
                                {-.16f, -.09f, -.15f}, {.56f, .21f, .14f},    {.21f, -.05f, -.30f}};

std::array<double, 3> bandNorms(auto get) {
  std::array<double, 3> n{};
  for (int k = 0; k < 9; ++k) n[lp::shBand(k)] += double(get(k)) * get(k);
  for (auto& v : n) v = std::sqrt(v);
  return n;
}

TEST(Published, GraceCathedral) {
  const lp::Image img = lp::loadImage(lpt::dataPath("probes/latlong_full/grace_latlong.exr"));
  ASSERT_EQ(img.width, 1024);
  const lp::Sh9 L = lp::project(lp::PanoramaView::rgbF32(img.rgb.data(), img.width, img.height));
  // One exposure scale for the file, from L00 averaged over the channels.
  double ratio[3], mean = 0;
  for (int ch = 0; ch < 3; ++ch) mean += (ratio[ch] = L.c[0][ch] / kGrace[0][ch]) / 3;
  for (int ch = 0; ch < 3; ++ch)
    EXPECT_NEAR(ratio[ch] / mean, 1.0, 0.01) << "L00 ratio, channel " << ch;
  // The table is printed to two decimals, so each entry is known to +-0.005: a band norm is
  // only known to lie in [lo, hi] (entries moved 0.005 towards / away from zero). That is up to
  // 1.5% of the small bands. We require our norm within 2% of that interval, and report the
  // deviation from the printed value itself (green band 2 is 2.1% off the printed norm and
  // inside its rounding interval).
  auto shrink = [](float v) {
    return v > 0 ? std::max(0.0f, v - 0.005f) : std::min(0.0f, v + 0.005f);
  };
  auto grow = [](float v) { return v >= 0 ? v + 0.005f : v - 0.005f; };
  for (int ch = 0; ch < 3; ++ch) {
    const auto ours = bandNorms([&](int k) { return L.c[k][ch] / mean; });
    const auto paper = bandNorms([&](int k) { return kGrace[k][ch]; });
    const auto lo = bandNorms([&](int k) { return shrink(kGrace[k][ch]); });
    const auto hi = bandNorms([&](int k) { return grow(kGrace[k][ch]); });
    for (int l = 0; l < 3; ++l) {
      const double outside = std::max({0.0, lo[l] - ours[l], ours[l] - hi[l]});
      EXPECT_LT(outside / paper[l], 0.02)
          << "band " << l << " channel " << ch << ": ours " << ours[l] << ", paper " << paper[l]
          << " in [" << lo[l] << ", " << hi[l] << "]";
      EXPECT_NEAR(ours[l] / paper[l], 1.0, 0.025) << "band " << l << " channel " << ch;
    }
  }
}

// R&H's worst case: a directional light (a 1.5-degree disc), whose nine-coefficient irradiance
// is off by 3/32 = 9.4% of the total intensity at most, against the brute-force integral.
TEST(Published, DirectionalLightWorstCase) {
  double power = 0;
  const lp::Image img = lpt::discEquirect(2048, 1024, glm::normalize(glm::dvec3(0.3, -0.5, 0.6)),
                                          1.5 * std::numbers::pi / 180, 100.0f, &power);
  const auto r = lp::compareIrradiance(img, lp::Layout::Equirect, 64, 32);
  EXPECT_GT(r.maxFracTotal, 0.085);
  EXPECT_LT(r.maxFracTotal, 0.10);
  // Closed form of the mean |error| for an ideal directional light: 3.07%
  // (1/2 of the integral over c in [-1,1] of |3/32 + c/2 + 15/32 c^2 - max(c,0)|).
  EXPECT_GT(r.meanFracTotal, 0.028);
  EXPECT_LT(r.meanFracTotal, 0.034);
  // The order-2 approximation of a clamped cosine dips below zero: ringing.
  EXPECT_LT(r.minShOverMean, 0.0);
}

// The same light taken out as a disc light: the error drops from 9.4% to at most 0.1%.
TEST(Published, DirectionalLightAsALight) {
  double power = 0;
  const lp::Image img = lpt::discEquirect(2048, 1024, glm::normalize(glm::dvec3(0.3, -0.5, 0.6)),
                                          1.5 * std::numbers::pi / 180, 100.0f, &power);
  const lp::LightOptions sun;
  const auto r =
      lp::compareIrradiance(img, lp::Layout::Equirect, 64, 32, {}, 0, glm::mat3(1.0f), {}, &sun);
  ASSERT_EQ(r.lights.size(), 1u);
  EXPECT_GT(r.maxFracTotal, 0.085);
  EXPECT_LT(r.maxFracTotalSun, 0.001);
}

// The real maps against the brute-force integral, SH alone and SH of the rest plus the lights
// (README's error table). Where a dominant compact source is found the targets are mean <= 0.6%
// and max <= 2% of the total intensity for the maps listed here; no map is worse than SH alone.
// The maps that miss the targets (royal_esplanade, and moonless_golf and the reduced Grace with
// one light only) are in README with the reason; they are held to "no worse than SH alone" here.
TEST(Published, SunAndSkyOnRealMaps) {
  struct Case {
    std::string file;
    lp::Layout layout;
    int lights;         // --lights K
    bool meetsTargets;  // a source is found and the targets hold
  };
  const Case cases[] = {
      {"equirect/pedestrian_overpass_1k.hdr", lp::Layout::Equirect, 1, true},
      {"equirect/quarry_01_1k.hdr", lp::Layout::Equirect, 1, true},
      {"probes/latlong_256x128/grace.hdr", lp::Layout::Equirect, 2, true},
      {"equirect/moonless_golf_1k.hdr", lp::Layout::Equirect, 2, true},
      {"equirect/blouberg_sunrise_2_1k.hdr", lp::Layout::Equirect, 1, false},
      {"equirect/moonless_golf_1k.hdr", lp::Layout::Equirect, 1, false},
      {"equirect/royal_esplanade_1k.hdr", lp::Layout::Equirect, 1, false},
      {"equirect/venice_sunset_1k.hdr", lp::Layout::Equirect, 1, false},
      {"probes/latlong_256x128/ennis.hdr", lp::Layout::Equirect, 1, false},
      {"probes/latlong_256x128/grace.hdr", lp::Layout::Equirect, 1, false},
      {"probes/latlong_256x128/pisa.hdr", lp::Layout::Equirect, 1, false},
      {"probes/latlong_256x128/uffizi.hdr", lp::Layout::Equirect, 1, false},
      {"probes/latlong_256x128/wells.hdr", lp::Layout::Equirect, 1, false},
      {"probes/latlong_full/grace_latlong.exr", lp::Layout::Equirect, 1, false},
      {"probes/beach_probe.hdr", lp::Layout::Angular, 1, false},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file + " --lights " + std::to_string(c.lights));
    const lp::Image img = lp::loadImage(lpt::dataPath(c.file));
    lp::LightOptions sun;
    sun.maxLights = c.lights;
    const auto r = lp::compareIrradiance(img, c.layout, 64, 32, {}, 0, glm::mat3(1.0f), {}, &sun);
    EXPECT_LE(r.meanFracTotalSun, r.meanFracTotal + 1e-6);
    EXPECT_LE(r.maxFracTotalSun, r.maxFracTotal + 1e-6);
    if (c.meetsTargets) {
      EXPECT_EQ(int(r.lights.size()), c.lights);
      EXPECT_LE(r.meanFracTotalSun, 0.006);
      EXPECT_LE(r.maxFracTotalSun, 0.02);
    }
    // No light: the coefficients are the whole map's, so the errors are SH alone's (up to the
    // float rounding of the basis sum against the quadratic form).
    if (r.lights.empty()) {
      EXPECT_NEAR(r.maxFracTotalSun, r.maxFracTotal, 1e-6);
    }
  }
}

}  // namespace
