#include "liveprobe/sh/lights.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace lp {

glm::vec3 lightIrradiance(const Light& light, glm::vec3 n) {
  const float c = glm::dot(n, light.dir);
  const float sa = std::sin(light.angularRadius), ca = std::cos(light.angularRadius);
  if (c >= sa) return light.power * (c * (1.0f + ca) * 0.5f);  // the whole disc is above
  if (c <= -sa) return glm::vec3(0.0f);                        // the whole disc is below
  // The disc straddles the horizon: the cap's form factor clipped by it, times its radiance
  // power / solid angle (solid angle 2 pi (1 - cos a) = 4 pi sin^2(a/2), without cancellation).
  const float sHalf = std::sin(0.5f * light.angularRadius);
  const glm::vec3 radiance = light.power / (4.0f * float(kPi) * sHalf * sHalf);
  if (sa < 0.02f) {
    // A small disc (under 1.15 degrees): the exact form's terms cancel to sa^3 in float, so the
    // disc is taken as flat (relative error O(a^2), under 4e-4 here): with t0 = -c / sin a,
    // E = L sa^2 [c (pi/2 - t0 sqrt(1 - t0^2) - asin t0) + (2/3) sa (1 - t0^2)^(3/2)].
    const float t0 = -c / sa, r = std::sqrt(std::max(0.0f, 1.0f - t0 * t0));
    const float f =
        c * (0.5f * float(kPi) - t0 * r - std::asin(t0)) + (2.0f / 3.0f) * sa * r * r * r;
    return radiance * std::max(sa * sa * f, 0.0f);
  }
  const float s = std::sqrt(std::max(0.0f, 1.0f - c * c));
  const float x = ca / sa, y = std::clamp(-x * c / s, -1.0f, 1.0f);
  const float q = s * std::sqrt(1.0f - y * y);
  const float f = (c * std::acos(y) - x * q) * sa * sa + std::atan(q / x);
  return radiance * std::max(f, 0.0f);
}

glm::vec3 evalIrradiance(const Sh9& residual, const std::vector<Light>& lights, glm::vec3 n) {
  glm::vec3 e = evalIrradiance(residual, n);
  for (const Light& l : lights) e += lightIrradiance(l, n);
  return e;
}

Sh9 lightsToSh(const std::vector<Light>& lights) {
  Sh9 out;
  for (const Light& l : lights) {
    const float ca = std::cos(l.angularRadius);
    const float band[3] = {1.0f, 0.5f * (1.0f + ca), 0.5f * ca * (1.0f + ca)};
    const auto y = shBasis(l.dir);
    for (int k = 0; k < kShCount; ++k) out.c[k] += l.power * (y[k] * band[shBand(k)]);
  }
  return out;
}

LightSplit rotateSplit(const LightSplit& split, const glm::mat3& rotation) {
  LightSplit out{rotateSh(split.residual, rotation), split.lights};
  for (Light& l : out.lights) l.dir = glm::normalize(rotation * l.dir);
  return out;
}

// ---- The direction index --------------------------------------------------------------------

namespace {
constexpr int kBucketRows = 180, kBucketCols = 360;  // one degree each
constexpr double kBucket = kPi / kBucketRows;

int bucketRow(double theta) { return std::clamp(int(theta / kBucket), 0, kBucketRows - 1); }
int bucketCol(double phi) {
  const int c = int(std::floor(phi / kBucket));
  return ((c % kBucketCols) + kBucketCols) % kBucketCols;
}
}  // namespace

/// Pixels (those with a solid angle) bucketed by the direction's polar angle and azimuth, as a
/// compressed table: the pixels of bucket b are pixels[start[b] .. start[b + 1]).
struct LightExtractor::Index {
  std::vector<std::uint32_t> start, pixels;

  explicit Index(const std::vector<SphereSample>& samples) {
    std::vector<std::uint32_t> bucketOf(samples.size(), UINT32_MAX);
    start.assign(std::size_t(kBucketRows) * kBucketCols + 1, 0);
    for (std::size_t i = 0; i < samples.size(); ++i) {
      if (samples[i].solidAngle <= 0.0f) continue;
      const glm::vec3 d = samples[i].dir;
      const double theta = std::acos(std::clamp(double(d.z), -1.0, 1.0)),
                   phi = std::atan2(double(d.y), double(d.x));
      bucketOf[i] = std::uint32_t(bucketRow(theta) * kBucketCols + bucketCol(phi));
      ++start[bucketOf[i] + 1];
    }
    for (std::size_t b = 1; b < start.size(); ++b) start[b] += start[b - 1];
    pixels.resize(start.back());
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < samples.size(); ++i)
      if (bucketOf[i] != UINT32_MAX) pixels[fill[bucketOf[i]]++] = std::uint32_t(i);
  }

  /// Calls f(pixel) for every pixel in buckets that may hold directions within `radius` of `d`
  /// (a superset of the cap; the caller tests the angle).
  template <class F>
  void forCap(glm::vec3 d, double radius, F&& f, std::uint32_t stride = 1) const {
    const double theta = std::acos(std::clamp(double(d.z), -1.0, 1.0)),
                 phi = std::atan2(double(d.y), double(d.x));
    const double lo = theta - radius, hi = theta + radius;
    const int r0 = bucketRow(std::max(0.0, lo)), r1 = bucketRow(std::min(kPi, hi));
    // Largest azimuth offset within the cap: asin(sin r / sin t) at the band's narrowest row;
    // every column where the cap reaches a pole or is wider than that.
    bool allCols = lo <= 0 || hi >= kPi;
    double dPhi = kPi;
    if (!allCols) {
      const double sinMin = std::min(std::sin(lo), std::sin(hi));
      if (std::sin(radius) >= sinMin)
        allCols = true;
      else
        dPhi = std::asin(std::sin(radius) / sinMin);
    }
    const int c0 = allCols ? 0 : int(std::floor((phi - dPhi) / kBucket)) - 1;
    const int c1 = allCols ? kBucketCols - 1 : int(std::floor((phi + dPhi) / kBucket)) + 1;
    const int span = std::min(c1 - c0, kBucketCols - 1);
    std::uint32_t skip = 0;  // with a stride, every stride-th pixel of the buckets in turn
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c0 + span; ++c) {
        const std::size_t b =
            std::size_t(r) * kBucketCols + std::size_t(bucketCol((c + 0.5) * kBucket));
        std::uint32_t k = start[b] + skip;
        for (; k < start[b + 1]; k += stride) f(pixels[k]);
        skip = k - start[b + 1];
      }
  }
};

LightExtractor::LightExtractor(const Projector& projector)
    : projector_(&projector), index_(std::make_unique<Index>(projector.samples())) {}
LightExtractor::~LightExtractor() = default;
LightExtractor::LightExtractor(LightExtractor&&) noexcept = default;
LightExtractor& LightExtractor::operator=(LightExtractor&&) noexcept = default;

// ---- Extraction -----------------------------------------------------------------------------

namespace {

float maxChannel(Rgb v) { return std::max(v.x, std::max(v.y, v.z)); }

/// Per-channel median (upper middle) of a list of values; the list is reordered.
Rgb channelMedian(std::vector<Rgb>& values) {
  Rgb m(0.0f);
  if (values.empty()) return m;
  const auto mid = values.begin() + std::ptrdiff_t(values.size() / 2);
  for (int c = 0; c < 3; ++c) {
    std::nth_element(values.begin(), mid, values.end(),
                     [c](const Rgb& a, const Rgb& b) { return a[c] < b[c]; });
    m[c] = (*mid)[c];
  }
  return m;
}

struct CapPixel {
  std::uint32_t index;
  float cosAngle;
  Rgb value;
};

}  // namespace

LightSplit LightExtractor::extract(const PanoramaView& frame, const Sh9& whole,
                                   const std::vector<float>& rowPeaks,
                                   const LightOptions& opt) const {
  LightSplit out{whole, {}};
  const float totalLum = luminance(whole.c[0]) / kY00;  // L00 = Y00 * integral of L
  if (opt.maxLights <= 0 || !(totalLum > 0.0f) || rowPeaks.size() != std::size_t(frame.height))
    return out;
  const auto& samples = projector_->samples();
  const std::size_t width = std::size_t(frame.width);
  const bool u8 = frame.format == PanoramaFormat::BgrU8 || frame.format == PanoramaFormat::RgbU8;
  const float clipLevel = u8 ? frame.decode[255] : INFINITY;
  std::unordered_map<std::uint32_t, Rgb> filled;  // residual values of the lights' pixels
  const auto value = [&](std::uint32_t i) {
    if (filled.empty()) return readPixel(frame, i);
    const auto it = filled.find(i);
    return it != filled.end() ? it->second : readPixel(frame, i);
  };
  std::vector<float> peaks = rowPeaks;
  const float maxRadius = glm::radians(opt.maxRadiusDeg);
  std::vector<CapPixel> cap;
  std::vector<Rgb> ring;

  for (int n = 0; n < opt.maxLights; ++n) {
    // 1. The peak: the brightest row, then its brightest pixel that the layout sees (a row's
    //    peak may lie outside the layout's image: then the row is re-ranked by what it holds).
    std::uint32_t peak = 0;
    float peakValue = -INFINITY;
    for (;;) {
      const auto row = std::size_t(std::max_element(peaks.begin(), peaks.end()) - peaks.begin());
      float best = -INFINITY;
      for (std::size_t j = 0; j < width; ++j) {
        const auto i = std::uint32_t(row * width + j);
        if (samples[i].solidAngle <= 0.0f) continue;
        const float v = maxChannel(value(i));
        if (v > best) best = v, peak = i;
      }
      if (best >= peaks[row]) {
        peakValue = best;
        break;
      }
      peaks[row] = best;  // the row's peak lay outside the image; rank it again
    }
    if (!(peakValue > 0.0f)) break;
    const glm::vec3 d0 = samples[peak].dir;
    const float peakLum = luminance(value(peak));
    if (!(peakLum > 0.0f)) break;
    // A clipped peak (an 8-bit frame at its maximum) has no known brightness: its core is the
    // clipped plateau itself, not what lies above a fraction of a value that is only a bound,
    // and its power, a lower bound, needs a smaller share.
    const bool peakClipped = peakValue >= clipLevel;
    const float minShare = peakClipped ? opt.minClippedShare : opt.minShare;
    const auto inCore = [&](Rgb v) {
      return peakClipped ? maxChannel(v) >= clipLevel : luminance(v) >= opt.coreFraction * peakLum;
    };
    const float pixelRadius = std::sqrt(samples[peak].solidAngle / float(kPi));
    const float glare = std::max(glm::radians(opt.glareDeg), 2.0f * pixelRadius);
    const float ringWidth = std::max(glm::radians(opt.ringDeg), 3.0f * pixelRadius);

    // 2. The core, in caps of growing reach (most sources are small, and the cost is the cap's
    //    pixels): the first reach that holds it, or not compact once it is wider than the
    //    largest. Then the cap is taken again around the core's centroid (the peak pixel may be
    //    on a plateau's edge), wide enough for the region and its ring.
    // `stride` > 1 takes every stride-th pixel of the index (each then stands for `stride`
    // pixels): the core's area needs a few thousand samples, not every pixel of a 4K frame.
    const auto gather = [&](glm::vec3 centre, float radius, std::uint32_t stride) {
      const float cosSearch = std::cos(radius);
      cap.clear();
      index_->forCap(
          centre, radius,
          [&](std::uint32_t i) {
            const float c = glm::dot(samples[i].dir, centre);
            if (c >= cosSearch) cap.push_back({i, c, value(i)});
          },
          stride);
    };
    constexpr float kCoreSamples = 4000.0f;
    float coreRadius = INFINITY;
    glm::vec3 centre = d0;
    // Each cap is centred on the centroid found so far; a reach that holds the core is measured
    // once more if its centroid moved by more than a pixel (a plateau seen from its edge).
    bool again = false;
    for (float reach = glm::radians(1.0f);;) {
      const float radius = 1.25f * reach + pixelRadius;  // a margin: a wide core shows as wider
      const float pixels = 4.0f * float(kPi) * std::sin(0.5f * radius) * std::sin(0.5f * radius) /
                           samples[peak].solidAngle;
      const auto stride = std::uint32_t(std::max(1.0f, pixels / kCoreSamples));
      const glm::vec3 from = centre;
      gather(from, radius, stride);
      double coreArea = 0;
      glm::dvec3 coreSum(0.0);
      for (const CapPixel& p : cap) {
        if (!inCore(p.value)) continue;
        const float lum = luminance(p.value);
        coreArea += double(samples[p.index].solidAngle) * stride;
        coreSum += glm::dvec3(samples[p.index].dir) * double(lum * samples[p.index].solidAngle);
      }
      coreRadius = float(std::acos(std::max(-1.0, 1.0 - coreArea / (2 * kPi)))) + pixelRadius;
      if (glm::length(coreSum) > 0.0) centre = glm::vec3(glm::normalize(coreSum));
      if (coreRadius > maxRadius) break;                // already wider than any light
      if (coreRadius <= reach || reach >= maxRadius) {  // held within this reach
        if (again || glm::dot(centre, from) >= std::cos(pixelRadius)) break;
        again = true;  // measure it once more around its centroid
        continue;
      }
      again = false;
      reach = std::min(2.0f * reach, maxRadius);
    }
    if (coreRadius > maxRadius) break;  // not compact: no (further) light
    const float regionGlare = std::max(glare, 0.5f * coreRadius);

    // 3-4. The region and the ring around it; the fill is the ring's median. A wide ring is
    //    sampled (~4000 pixels), and so is a first estimate of the light's share: a source that
    //    plainly falls short is dropped before its region is read whole.
    const float cosRegion = std::cos(coreRadius + regionGlare),
                cosRing = std::cos(coreRadius + regionGlare + ringWidth);
    const float outer = coreRadius + regionGlare + ringWidth + pixelRadius;
    const auto outerStride = std::uint32_t(
        std::max(1.0f, 4.0f * float(kPi) * std::sin(0.5f * outer) * std::sin(0.5f * outer) /
                           samples[peak].solidAngle / kCoreSamples));
    gather(centre, outer, outerStride);
    ring.clear();
    for (const CapPixel& p : cap)
      if (p.cosAngle < cosRegion && p.cosAngle >= cosRing) ring.push_back(p.value);
    const Rgb fill = channelMedian(ring);
    if (outerStride > 1) {
      double estimate = 0;
      for (const CapPixel& p : cap)
        if (p.cosAngle >= cosRegion)
          estimate += double(luminance(glm::max(p.value - fill, Rgb(0.0f)))) *
                      samples[p.index].solidAngle * outerStride;
      if (estimate < 0.5 * minShare * totalLum) break;            // far below the share: no light
      gather(centre, coreRadius + regionGlare + pixelRadius, 1);  // the region, every pixel
    }

    // 5. The light: what lies above the fill.
    glm::dvec3 power(0.0), centroid(0.0);
    float maxExcess = 0.0f;
    bool clipped = false;
    for (const CapPixel& p : cap) {
      if (p.cosAngle < cosRegion) continue;
      const Rgb excess = glm::max(p.value - fill, Rgb(0.0f));
      const double dw = samples[p.index].solidAngle;
      power += glm::dvec3(excess) * dw;
      centroid += glm::dvec3(samples[p.index].dir) * (double(luminance(excess)) * dw);
      maxExcess = std::max(maxExcess, luminance(excess));
      clipped = clipped || maxChannel(p.value) >= clipLevel;
    }
    Light light;
    light.power = Rgb(power);
    light.share = luminance(light.power) / totalLum;
    if (!(light.share >= minShare) || glm::length(centroid) <= 0.0) break;
    light.dir = glm::vec3(glm::normalize(centroid));
    light.clipped = clipped;
    double halfMaxArea = 0;
    for (const CapPixel& p : cap)
      if (p.cosAngle >= cosRegion &&
          luminance(glm::max(p.value - fill, Rgb(0.0f))) >= 0.5f * maxExcess)
        halfMaxArea += samples[p.index].solidAngle;
    light.angularRadius = float(std::acos(std::max(-1.0, 1.0 - halfMaxArea / (2 * kPi))));

    // Commit: the coefficients lose exactly what the light took (summed in double); for the
    // next light, the region keeps min(L, fill).
    std::array<glm::dvec3, kShCount> taken{};
    for (const CapPixel& p : cap) {
      if (p.cosAngle < cosRegion) continue;
      const glm::dvec3 excess(glm::max(p.value - fill, Rgb(0.0f)));
      const auto w = projector_->pixelWeights(p.index);
      for (int k = 0; k < kShCount; ++k) taken[k] += excess * double(w[k]);
    }
    for (int k = 0; k < kShCount; ++k) out.residual.c[k] -= Rgb(taken[k]);
    out.lights.push_back(light);
    if (n + 1 == opt.maxLights) break;
    std::vector<std::size_t> rows;
    for (const CapPixel& p : cap) {
      if (p.cosAngle < cosRegion) continue;
      filled[p.index] = glm::min(p.value, fill);
      rows.push_back(p.index / width);
    }
    // The rows the light touched: their peaks from what is left.
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    for (const std::size_t r : rows) {
      float m = 0.0f;
      for (std::size_t j = 0; j < width; ++j)
        if (samples[r * width + j].solidAngle > 0.0f)
          m = std::max(m, maxChannel(value(std::uint32_t(r * width + j))));
      peaks[r] = m;
    }
  }
  return out;
}

LightSplit projectWithLights(const PanoramaView& frame, const LightOptions& options,
                             Executor* executor) {
  const Projector projector(frame.layout, frame.width, frame.height);
  std::vector<float> peaks;
  const Sh9 whole = projector.project(frame, executor, &peaks);
  return LightExtractor(projector).extract(frame, whole, peaks, options);
}

}  // namespace lp
