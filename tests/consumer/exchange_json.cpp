// Links liveprobe::exchange from an install. Projects Debevec's Grace Cathedral probe, writes its
// coefficients as liveprobe's JSON, reads the text back and checks that every value comes back
// as the same float (the format writes each float's shortest round-tripping decimal).
#include <liveprobe/capture/image.h>
#include <liveprobe/exchange/coeffs_io.h>
#include <liveprobe/sh/error.h>
#include <liveprobe/sh/projector.h>

#include <cstdio>
#include <string>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: exchange_json GRACE_LATLONG.exr\n");
    return 2;
  }
  try {
    const lp::Image img = lp::loadImage(argv[1]);
    const lp::Sh9 L = lp::project(lp::PanoramaView::rgbF32(img.rgb.data(), img.width, img.height));
    const std::string text = lp::coefficientsJson(L).dump();
    const lp::Sh9 back = lp::coefficientsFromJson(nlohmann::json::parse(text), "the written JSON");
    int differ = 0;
    for (int k = 0; k < lp::kShCount; ++k)
      for (int ch = 0; ch < 3; ++ch)
        if (back.c[k][ch] != L.c[k][ch])
          ++differ,
              std::printf("%s channel %d: wrote %.9g, read %.9g\n",
                          std::string(lp::kShNames[k]).c_str(), ch, L.c[k][ch], back.c[k][ch]);
    std::printf("exchange_json: %s\n", differ ? "the JSON does not round-trip" : "round-trips");
    return differ ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "exchange_json: %s\n", e.what());
    return 1;
  }
}
