#include "liveprobe/capture/resample.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include "liveprobe/sh/error.h"

namespace lp {

Image resampleToEquirect(const Image& frame, const LayoutSpec& spec, int width, int height) {
  Image out(width, height);
  // Where each output pixel lands in the frame. A lens (or a ball through one) asks OpenCV for
  // all at once, and a stream of one lens and size asks once: the last answer is kept per thread.
  struct Landing {
    std::weak_ptr<const LensModel> lens;  ///< weak: a new lens at a freed one's address differs
    int frameWidth = 0, frameHeight = 0, width = 0, height = 0;
    std::vector<glm::vec2> at;
  };
  thread_local Landing last;
  const Landing key{spec.lens, frame.width, frame.height, width, height, {}};
  const bool kept = spec.lens && last.lens.lock() == spec.lens &&
                    last.frameWidth == key.frameWidth && last.frameHeight == key.frameHeight &&
                    last.width == width && last.height == height;
  if (!kept) {
    const auto grid = equirectSamples(width, height);
    std::vector<glm::vec3> dirs(grid.size());
    for (std::size_t i = 0; i < grid.size(); ++i) dirs[i] = grid[i].dir;
    last = key;
    last.at.resize(grid.size());
    layoutPixels(spec, frame.width, frame.height, dirs.data(), dirs.size(), last.at.data());
    if (!spec.lens) last.lens.reset();
  }
  for (std::size_t i = 0; i < last.at.size(); ++i) {
    const std::optional<glm::vec2> px =
        std::isfinite(last.at[i].x) ? std::optional(last.at[i]) : std::nullopt;
    if (!px) continue;
    // Bilinear between pixel centres, clamped at the frame's edges.
    const float fx = std::clamp(px->x - 0.5f, 0.0f, float(frame.width - 1));
    const float fy = std::clamp(px->y - 0.5f, 0.0f, float(frame.height - 1));
    const int x0 = int(fx), y0 = int(fy);
    const int x1 = std::min(x0 + 1, frame.width - 1), y1 = std::min(y0 + 1, frame.height - 1);
    const float ax = fx - x0, ay = fy - y0;
    for (int c = 0; c < 3; ++c)
      out.rgb[3 * i + c] =
          (1 - ay) * ((1 - ax) * frame.pixel(x0, y0)[c] + ax * frame.pixel(x1, y0)[c]) +
          ay * ((1 - ax) * frame.pixel(x0, y1)[c] + ax * frame.pixel(x1, y1)[c]);
  }
  return out;
}

Image reduceEquirect(const float* rgb, int width, int height, int f) {
  Image out;
  reduceEquirect(rgb, width, height, f, out);
  return out;
}

void reduceEquirect(const float* rgb, int width, int height, int f, Image& out) {
  if (f < 1 || width % f || height % f)
    throw Error("reduce: " + std::to_string(width) + "x" + std::to_string(height) +
                " is not a multiple of " + std::to_string(f));
  const int w = width / f, h = height / f;
  out.width = w, out.height = h;
  out.rgb.resize(std::size_t(w) * std::size_t(h) * 3);
  for (int I = 0; I < h; ++I) {
    float* acc = out.pixel(0, I);  // the output row gathers the sums
    std::fill(acc, acc + std::size_t(w) * 3, 0.0f);
    double total = 0;
    for (int r = 0; r < f; ++r) {
      const int i = I * f + r;
      // Row weight: the row's solid angle (all pixels of a row have the same).
      const float wt = float(std::cos(kPi * i / height) - std::cos(kPi * (i + 1) / height));
      total += wt;
      const float* row = rgb + std::size_t(i) * width * 3;
      for (int J = 0; J < w; ++J) {
        float s0 = 0, s1 = 0, s2 = 0;
        for (int q = 0; q < f; ++q, row += 3) s0 += row[0], s1 += row[1], s2 += row[2];
        acc[3 * J] += wt * s0, acc[3 * J + 1] += wt * s1, acc[3 * J + 2] += wt * s2;
      }
    }
    const float norm = float(1.0 / (total * f));
    for (std::size_t x = 0; x < std::size_t(w) * 3; ++x) acc[x] *= norm;
  }
}

bool displayDrawsAsIs(const LayoutSpec& layout) {
  return layout.layout == Layout::Equirect || layout.layout == Layout::Angular;
}

Layout displayLayout(const LayoutSpec& layout) {
  return displayDrawsAsIs(layout) ? layout.layout : Layout::Equirect;
}

Image displayEquirect(const Image& frame, const LayoutSpec& layout) {
  return resampleToEquirect(frame, layout, 1024, 512);
}

}  // namespace lp
