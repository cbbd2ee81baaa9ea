// libFuzzer target: the exposure bracket's merge over a stream of 8-bit frames, the turn between
// them included. The input chooses the frame size (any, from 1x1), the window (1 to 5 frames),
// each frame's exposure and sequence step, and the pixels: a pattern from the input, shifted by
// a chosen number of columns per frame (a camera turning about the vertical, which the merge
// estimates and undoes). Every merge is RGB floats of the frame's size, finite and
// non-negative, with a confidence in [0, 1]; or lp::Error.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "liveprobe/hdr/merge.h"
#include "liveprobe/sh/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 6) return 0;
  const int w = 1 + data[0] % 128, h = 1 + data[1] % 64;
  const int window = 1 + data[2] % 5, frames = 1 + data[3] % 12, shift = data[4] % 7 - 3;
  const bool equirect = data[5] & 1;
  const std::uint8_t* pattern = data + 6;
  const std::size_t patternSize = size - 6;
  try {
    lp::BracketMerger merger({.frames = window, .equirect = equirect});
    lp::Frame out;
    std::uint64_t sequence = 0;
    for (int n = 0; n < frames; ++n) {
      const std::uint8_t step = patternSize ? pattern[std::size_t(n) % patternSize] : 0;
      lp::Frame f;
      f.format = lp::PanoramaFormat::BgrU8;
      f.width = w, f.height = h;
      f.radianceScale = std::exp2(double(step % 16) - 8.0);  // 1/256 to 128
      f.sequence = sequence += 1 + step / 128;
      f.bgr8.resize(std::size_t(w) * std::size_t(h) * 3);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          for (int c = 0; c < 3; ++c) {
            const int sx = ((x - shift * n) % w + w) % w;
            const std::size_t i = (std::size_t(y) * std::size_t(w) + std::size_t(sx)) * 3 + c;
            f.bgr8[(std::size_t(y) * std::size_t(w) + std::size_t(x)) * 3 + std::size_t(c)] =
                patternSize ? std::uint8_t(pattern[i % patternSize] + (step % 16) * 16) : 0;
          }
      const lp::FrameConfidence conf = merger.add(f, out);
      if (out.width != w || out.height != h || out.rgb.size() != f.bgr8.size()) std::abort();
      for (float v : out.rgb)
        if (!std::isfinite(v) || v < 0) std::abort();
      const double c = conf.value();
      if (!(c >= 0 && c <= 1)) std::abort();
    }
  } catch (const lp::Error&) {
  }
  return 0;
}
