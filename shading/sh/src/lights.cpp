#include "liveprobe/sh/lights.h"

#include <algorithm>
#include <cmath>
#include <optional>
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
constexpr double kMargin = 1e-5;  // radians: float directions against double bounds

double thetaOf(glm::vec3 d) { return std::acos(std::clamp(double(d.z), -1.0, 1.0)); }
double phiOf(glm::vec3 d) { return std::atan2(double(d.y), double(d.x)); }
int bucketRow(double theta) { return std::clamp(int(theta / kBucket), 0, kBucketRows - 1); }
int bucketCol(double phi) {
  const int c = int(std::floor(phi / kBucket));
  return ((c % kBucketCols) + kBucketCols) % kBucketCols;
}

/// The cap of `radius` around `d` in polar angle and azimuth: which polar angles it reaches, and
/// at each band of polar angles the half-width of its azimuths.
struct CapBounds {
  double theta, phi, radius, cosR, cosC, sinC, widest;

  CapBounds(glm::vec3 d, double r)
      : theta(thetaOf(d)),
        phi(phiOf(d)),
        radius(r + kMargin),
        cosR(std::cos(radius)),
        cosC(std::cos(theta)),
        sinC(std::sin(theta)) {
    // Where the cap is widest: cos t = cos theta / cos R (there its half-width is
    // asin(sin R / sin theta)).
    widest = std::abs(cosC / cosR) <= 1.0 ? std::acos(cosC / cosR) : -1.0;
  }
  double lo() const { return std::max(0.0, theta - radius); }
  double hi() const { return std::min(kPi, theta + radius); }
  /// Half the azimuth span at polar angle t (pi: every azimuth; negative: none).
  double halfSpan(double t) const {
    const double st = std::sin(t);
    if (st * sinC <= 1e-12) return std::cos(t - theta) >= cosR ? kPi : -1.0;
    const double c = (cosR - std::cos(t) * cosC) / (st * sinC);
    return c <= -1.0 ? kPi : c > 1.0 ? -1.0 : std::acos(c);
  }
  /// The half-span at polar angle t clamped to the cap's: a band's edge.
  double edge(double t) const { return halfSpan(std::clamp(t, theta - radius, theta + radius)); }
  /// The largest half-span over the band of polar angles [a, b] whose edges' half-spans are ea
  /// and eb (the cap's width is unimodal in t), with the margin.
  double band(double a, double b, double ea, double eb) const {
    double span = std::max(ea, eb);
    if (widest >= a && widest <= b) span = std::max(span, halfSpan(widest));
    return span < 0.0 ? span : span + kMargin;
  }
  double band(double a, double b) const { return band(a, b, edge(a), edge(b)); }
};
}  // namespace

/// Which pixels lie near a direction. Equirect frames need no table: row i covers polar angles
/// [pi i/H, pi (i+1)/H] and column j azimuths [2 pi j/W, 2 pi (j+1)/W] (liveprobe/sh/sh.h), so a
/// cap is one run of columns per row (two where it wraps). Other layouts bucket their pixels (those
/// with a solid angle) by polar angle and azimuth, one degree each, as runs of consecutive pixels
/// of one row: the runs of bucket b are runs[start[b] .. start[b + 1]), in pixel order. Either
/// way a cap is read in runs along image rows, which the prefetchers follow.
struct LightExtractor::Index {
  struct Run {
    std::uint32_t row, col, count;
  };
  bool equirect;
  std::uint32_t width, height, longest = 0;
  std::vector<std::uint32_t> start;
  std::vector<Run> runs;

  explicit Index(const Projector& projector)
      : equirect(projector.spec().layout == Layout::Equirect),
        width(std::uint32_t(projector.width())),
        height(std::uint32_t(projector.height())) {
    if (equirect) {
      longest = width;
      return;
    }
    const auto& samples = projector.samples();
    std::vector<std::uint32_t> bucketOf;  // per run, in pixel order
    std::vector<Run> found;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      if (samples[i].solidAngle <= 0.0f) continue;
      const glm::vec3 d = samples[i].dir;
      const auto b = std::uint32_t(bucketRow(thetaOf(d)) * kBucketCols + bucketCol(phiOf(d)));
      const auto row = std::uint32_t(i / width), col = std::uint32_t(i % width);
      if (!found.empty() && bucketOf.back() == b && found.back().row == row &&
          found.back().col + found.back().count == col)
        ++found.back().count;
      else
        found.push_back({row, col, 1}), bucketOf.push_back(b);
    }
    start.assign(std::size_t(kBucketRows) * kBucketCols + 1, 0);
    for (const std::uint32_t b : bucketOf) ++start[b + 1];
    for (std::size_t b = 1; b < start.size(); ++b) start[b] += start[b - 1];
    runs.resize(found.size());
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t r = 0; r < found.size(); ++r) {
      runs[fill[bucketOf[r]]++] = found[r];
      longest = std::max(longest, found[r].count);
    }
  }

  /// The bands (image rows for equirect, bucket rows otherwise) [first, last] the cap reaches.
  std::pair<int, int> bands(const CapBounds& cap) const {
    if (equirect) {
      const double perRow = double(height) / kPi;
      return {std::clamp(int(cap.lo() * perRow), 0, int(height) - 1),
              std::clamp(int(cap.hi() * perRow), 0, int(height) - 1)};
    }
    return {bucketRow(cap.lo()), bucketRow(cap.hi())};
  }

  /// Calls f(run) for runs that hold every pixel whose direction lies in `cap` (and a few more
  /// near it; the caller tests the angle). With step > 1 only runs on every step-th image row (a
  /// lattice sample, with the caller taking every step-th column).
  template <class F>
  void forCap(const CapBounds& cap, std::uint32_t step, F&& f) const {
    const auto [b0, b1] = bands(cap);
    if (equirect) {
      const double rowAngle = kPi / height, colAngle = 2 * kPi / width;
      double top = cap.edge(b0 * rowAngle);  // each row's upper edge is the last one's lower
      for (int i = b0; i <= b1; ++i) {
        if (step > 1 && std::uint32_t(i) % step != 0) continue;
        if (step > 1) top = cap.edge(i * rowAngle);
        const double bottom = cap.edge((i + 1) * rowAngle);
        const double span = cap.band(i * rowAngle, (i + 1) * rowAngle, top, bottom);
        top = bottom;
        if (span < 0.0) continue;
        const auto row = std::uint32_t(i);
        const auto c0 = std::int64_t(std::floor((cap.phi - span) / colAngle));
        const auto c1 = std::int64_t(std::floor((cap.phi + span) / colAngle));
        if (span >= kPi || c1 - c0 + 1 >= std::int64_t(width)) {
          f(Run{row, 0, width});
          continue;
        }
        const auto w = std::int64_t(width);
        const auto from = std::uint32_t(((c0 % w) + w) % w);
        const auto count = std::uint32_t(c1 - c0 + 1);
        if (from + count <= width) {
          f(Run{row, from, count});
        } else {  // wraps past the last column
          f(Run{row, from, width - from});
          f(Run{row, 0, from + count - width});
        }
      }
      return;
    }
    for (int r = b0; r <= b1; ++r) {
      const double span = cap.band(r * kBucket, (r + 1) * kBucket);
      if (span < 0.0) continue;
      const bool all = span >= kPi;
      const int c0 = all ? 0 : int(std::floor((cap.phi - span) / kBucket));
      const int c1 = all ? kBucketCols - 1 : int(std::floor((cap.phi + span) / kBucket));
      for (int c = c0; c <= std::min(c1, c0 + kBucketCols - 1); ++c) {
        const std::size_t bucket =
            std::size_t(r) * kBucketCols + std::size_t(bucketCol((c + 0.5) * kBucket));
        for (std::uint32_t k = start[bucket]; k < start[bucket + 1]; ++k)
          if (step == 1 || runs[k].row % step == 0) f(runs[k]);
      }
    }
  }
};

LightExtractor::LightExtractor(const Projector& projector)
    : projector_(&projector), index_(std::make_unique<Index>(projector)) {}
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

/// Lattice step that leaves at most about `target` samples (and more than a quarter of it) of a
/// cap of `radius` around pixels of solid angle `pixel`: each sample stands for step^2 pixels.
std::uint32_t latticeStep(float radius, float pixel, float target) {
  const float s = std::sin(0.5f * radius);
  const float pixels = 4.0f * float(kPi) * s * s / pixel;
  return std::uint32_t(std::max(1.0f, std::ceil(std::sqrt(pixels / target))));
}

struct Sampled {
  Rgb value;
  float weight;  ///< dw times the lattice step squared
};

/// What the region gives the light.
struct RegionSums {
  glm::dvec3 power{0.0}, centroid{0.0};
  std::array<glm::dvec3, kShCount> taken{};  ///< the coefficients of the light's pixels
  float maxExcess = 0.0f;
  bool clipped = false;
  std::vector<std::pair<float, float>> lit;         ///< excess luminance, dw per lit pixel
  std::vector<std::pair<std::uint32_t, Rgb>> keep;  ///< min(L, fill) per pixel, for the next light
};

}  // namespace

/// One extract() call's state: the frame, the row peaks as the lights found so far leave them,
/// the pixels those lights filled, and the buffers a run is read into. Each step of the search
/// for one light is a member.
struct LightExtractor::Search {
  const PanoramaView& frame;
  const Projector& projector;
  const Index& index;
  const std::vector<SphereSample>& samples;
  const LightOptions& opt;
  const std::size_t width;
  const float clipLevel;  ///< an 8-bit frame's maximum (infinite for float frames)
  const float totalLum;   ///< the map's luminance power
  std::unordered_map<std::uint32_t, Rgb> filled;  ///< residual values of the lights' pixels
  std::vector<Rgb> values, excess, rowValues;
  std::vector<float> lums;
  const std::vector<float>* peaks;  ///< the row peaks, copied only once a light changes them
  std::vector<float> ownPeaks;
  std::vector<Rgb> ring;
  std::vector<Sampled> region;

  Search(const LightExtractor& x, const PanoramaView& f, const std::vector<float>& rowPeaks,
         const LightOptions& o, float total)
      : frame(f),
        projector(*x.projector_),
        index(*x.index_),
        samples(projector.samples()),
        opt(o),
        width(std::size_t(f.width)),
        clipLevel(f.format == PanoramaFormat::BgrU8 || f.format == PanoramaFormat::RgbU8
                      ? f.decode[255]
                      : INFINITY),
        totalLum(total),
        values(index.longest),
        excess(index.longest),
        rowValues(width),
        lums(index.longest),
        peaks(&rowPeaks) {}

  /// A run's values, with the earlier lights' pixels as they left them.
  void readRun(const Index::Run& r, Rgb* out) const {
    readPixels(frame, r.row, r.col, r.count, out);
    if (filled.empty()) return;
    for (std::uint32_t k = 0; k < r.count; ++k)
      if (const auto it = filled.find(std::uint32_t(r.row * width + r.col + k)); it != filled.end())
        out[k] = it->second;
  }

  /// Calls f(sample, cos angle to centre, value, weight) for each pixel of the cap, on a lattice
  /// of the given step (weight: the pixel's solid angle times step^2).
  template <class F>
  void forCap(glm::vec3 centre, float radius, std::uint32_t step, F&& f) {
    const float cosRadius = std::cos(radius), area = float(step * step);
    index.forCap(CapBounds(centre, radius), step, [&](const Index::Run& r) {
      const std::uint32_t k0 = step == 1 ? 0 : (step - r.col % step) % step;
      if (k0 >= r.count) return;
      readRun(r, values.data());
      const SphereSample* s = samples.data() + r.row * width + r.col;
      for (std::uint32_t k = k0; k < r.count; k += step) {
        const float c = glm::dot(s[k].dir, centre);
        if (c >= cosRadius) f(s[k], c, values[k], s[k].solidAngle * area);
      }
    });
  }

  /// A row's largest channel value among the pixels the layout sees, and where it is (the row's
  /// values stay in rowValues).
  std::pair<float, std::uint32_t> rowPeak(std::size_t row) {
    readRun({std::uint32_t(row), 0, std::uint32_t(width)}, rowValues.data());
    const SphereSample* s = samples.data() + row * width;
    float best = -INFINITY;
    std::uint32_t at = 0;
    for (std::size_t j = 0; j < width; ++j) {
      const float v = maxChannel(rowValues[j]);
      if (s[j].solidAngle > 0.0f && v > best) best = v, at = std::uint32_t(row * width + j);
    }
    return {best, at};
  }

  void setPeak(std::size_t row, float v) {
    if (ownPeaks.empty()) ownPeaks = *peaks, peaks = &ownPeaks;
    ownPeaks[row] = v;
  }

  /// Where a light's search starts.
  struct Peak {
    std::uint32_t pixel = 0;
    float value = -INFINITY, lum = 0;
  };
  /// 1. The brightest row, then its brightest pixel that the layout sees (a row's peak may lie
  ///    outside the layout's image: then the row is ranked again by what it holds).
  Peak findPeak() {
    for (;;) {
      const auto row = std::size_t(std::max_element(peaks->begin(), peaks->end()) - peaks->begin());
      const auto [best, at] = rowPeak(row);
      if (best >= (*peaks)[row])
        return {at, best, best > 0.0f ? luminance(rowValues[at % width]) : 0.0f};
      setPeak(row, best);
    }
  }

  /// The scales one light is measured at, from its peak.
  struct Scales {
    bool clipped;  ///< the peak is at the 8-bit maximum
    float minShare, pixelDw, pixelRadius, glare, ringWidth;
  };
  Scales scalesAt(const Peak& peak) const {
    // A clipped peak has no known brightness: its power, a lower bound, needs a smaller share.
    Scales sc{};
    sc.clipped = peak.value >= clipLevel;
    sc.minShare = sc.clipped ? opt.minClippedShare : opt.minShare;
    // A light the frame before had, here again: held down to a fraction of the share.
    const glm::vec3 dir = samples[peak.pixel].dir;
    const float nearHeld = std::cos(glm::radians(opt.heldDeg));
    for (const glm::vec3& h : opt.held)
      if (glm::dot(dir, h) >= nearHeld) {
        sc.minShare *= opt.heldFraction;
        break;
      }
    sc.pixelDw = samples[peak.pixel].solidAngle;
    sc.pixelRadius = std::sqrt(sc.pixelDw / float(kPi));
    sc.glare = std::max(glm::radians(opt.glareDeg), 2.0f * sc.pixelRadius);
    sc.ringWidth = std::max(glm::radians(opt.ringDeg), 3.0f * sc.pixelRadius);
    return sc;
  }

  /// 2. The core (a clipped peak's core is its clipped plateau, not what lies above a fraction of
  ///    a value that is only a bound), in caps of growing reach (most sources are small, and the
  ///    cost is the cap's pixels): the first reach that holds it. Each cap is centred on the
  ///    centroid found so far; a reach that holds the core is measured once more if its centroid
  ///    moved by more than a pixel (a plateau seen from its edge). A cap of many pixels is read
  ///    on a lattice of at most about kCoreSamples: the core's area and centre need a thousand
  ///    samples, not every pixel of a 4K frame (its exact centroid and size come from the
  ///    region's every pixel). Returns the core's radius (over the largest: not compact) and
  ///    moves `centre` to its centroid.
  static constexpr float kCoreSamples = 1000.0f;
  float measureCore(const Peak& peak, const Scales& sc, glm::vec3& centre) {
    const auto inCore = [&](Rgb v) {
      return sc.clipped ? maxChannel(v) >= clipLevel : luminance(v) >= opt.coreFraction * peak.lum;
    };
    const float maxRadius = glm::radians(opt.maxRadiusDeg);
    float coreRadius = INFINITY;
    bool again = false;
    for (float reach = glm::radians(1.0f);;) {
      const float radius = 1.25f * reach + sc.pixelRadius;  // a wide core shows as wider
      const glm::vec3 from = centre;
      double coreArea = 0;
      glm::dvec3 coreSum(0.0);
      forCap(from, radius, latticeStep(radius, sc.pixelDw, kCoreSamples),
             [&](const SphereSample& s, float, Rgb v, float w) {
               if (!inCore(v)) return;
               coreArea += w;
               coreSum += glm::dvec3(s.dir) * double(luminance(v) * w);
             });
      coreRadius = float(std::acos(std::max(-1.0, 1.0 - coreArea / (2 * kPi)))) + sc.pixelRadius;
      if (glm::length(coreSum) > 0.0) centre = glm::vec3(glm::normalize(coreSum));
      if (coreRadius > maxRadius) return coreRadius;    // already wider than any light
      if (coreRadius <= reach || reach >= maxRadius) {  // held within this reach
        if (again || glm::dot(centre, from) >= std::cos(sc.pixelRadius)) return coreRadius;
        again = true;
        continue;
      }
      again = false;
      reach = std::min(2.0f * reach, maxRadius);
    }
  }

  /// 3-4. The ring around the region; the fill is its median. A wide ring is sampled (on a
  ///    lattice, as the core), and so is a first estimate of the light's share: a source that
  ///    plainly falls short is dropped (nullopt) before its region is read whole.
  std::optional<Rgb> ringFill(glm::vec3 centre, float regionRadius, const Scales& sc) {
    const float cosRegion = std::cos(regionRadius);
    const float outer = regionRadius + sc.ringWidth;
    const std::uint32_t outerStep = latticeStep(outer + sc.pixelRadius, sc.pixelDw, kCoreSamples);
    ring.clear();
    region.clear();
    forCap(centre, outer, outerStep, [&](const SphereSample&, float c, Rgb v, float w) {
      if (c < cosRegion)
        ring.push_back(v);
      else if (outerStep > 1)
        region.push_back({v, w});
    });
    const Rgb fill = channelMedian(ring);
    if (outerStep > 1) {
      double estimate = 0;
      for (const Sampled& p : region)
        estimate += double(luminance(glm::max(p.value - fill, Rgb(0.0f)))) * p.weight;
      if (estimate < 0.5 * sc.minShare * totalLum) return std::nullopt;
    }
    return fill;
  }

  /// 5. The light from every pixel of the region: what lies above the fill, and the coefficients
  ///    it takes from the map (with the projector's own weights, summed in double, so residual +
  ///    light is the whole map). `keep`: also what each pixel leaves for the next light.
  RegionSums measureRegion(glm::vec3 centre, float regionRadius, const Scales& sc, Rgb fill,
                           bool keep) {
    const float cosRegion = std::cos(regionRadius);
    const float regionReach = regionRadius + sc.pixelRadius;
    const float regionHalf = std::sin(0.5f * regionReach);
    RegionSums got;
    got.lit.reserve(std::size_t(8.0f * float(kPi) * regionHalf * regionHalf / sc.pixelDw));  // 2x
    index.forCap(CapBounds(centre, regionReach), 1, [&](const Index::Run& r) {
      readRun(r, values.data());
      const std::size_t first = r.row * width + r.col;
      const SphereSample* s = samples.data() + first;
      // Branch-free, into locals (float over a run, double beyond).
      Rgb runPower(0.0f);
      glm::vec3 runCentroid(0.0f);
      float runMax = 0.0f;
      bool runClipped = false;
      for (std::uint32_t k = 0; k < r.count; ++k) {
        const bool in = glm::dot(s[k].dir, centre) >= cosRegion;
        const Rgb e = in ? glm::max(values[k] - fill, Rgb(0.0f)) : Rgb(0.0f);
        const float lum = luminance(e), dw = s[k].solidAngle;
        excess[k] = e;
        lums[k] = lum;
        runPower += e * dw;
        runCentroid += s[k].dir * (lum * dw);
        runMax = std::max(runMax, lum);
        runClipped = runClipped || (in && maxChannel(values[k]) >= clipLevel);
      }
      got.clipped = got.clipped || runClipped;
      if (keep)
        for (std::uint32_t k = 0; k < r.count; ++k)
          if (glm::dot(s[k].dir, centre) >= cosRegion)
            got.keep.emplace_back(std::uint32_t(first + k), glm::min(values[k], fill));
      if (runPower == Rgb(0.0f)) return;
      std::uint32_t lo = r.count, hi = 0;  // the pixels with an excess (lum > 0: some channel)
      for (std::uint32_t k = 0; k < r.count; ++k)
        if (lums[k] > 0.0f)
          got.lit.emplace_back(lums[k], s[k].solidAngle), lo = std::min(lo, k), hi = k;
      got.maxExcess = std::max(got.maxExcess, runMax);
      got.power += glm::dvec3(runPower);
      got.centroid += glm::dvec3(runCentroid);
      projector.addPixels(r.row, r.col + lo, excess.data() + lo, hi - lo + 1, got.taken);
    });
    return got;
  }

  /// The light the region's sums describe; its size is the area at half the largest excess.
  Light lightOf(const RegionSums& got) const {
    Light light;
    light.power = Rgb(got.power);
    light.share = luminance(light.power) / totalLum;
    light.dir = glm::length(got.centroid) > 0.0 ? glm::vec3(glm::normalize(got.centroid))
                                                : glm::vec3(0.0f, 0.0f, 1.0f);
    light.clipped = got.clipped;
    double halfMaxArea = 0;
    for (const auto& [lum, dw] : got.lit)
      if (lum >= 0.5f * got.maxExcess) halfMaxArea += dw;
    light.angularRadius = float(std::acos(std::max(-1.0, 1.0 - halfMaxArea / (2 * kPi))));
    return light;
  }

  /// For the next light: the region keeps min(L, fill), and the rows it touched get their peaks
  /// from what is left.
  void fillRegion(const RegionSums& got) {
    std::vector<std::size_t> rows;
    for (const auto& [i, v] : got.keep) {
      filled[i] = v;
      rows.push_back(i / width);
    }
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    for (const std::size_t r : rows) setPeak(r, std::max(0.0f, rowPeak(r).first));
  }
};

LightSplit LightExtractor::extract(const PanoramaView& frame, const Sh9& whole,
                                   const std::vector<float>& rowPeaks,
                                   const LightOptions& opt) const {
  LightSplit out{whole, {}};
  const float totalLum = luminance(whole.c[0]) / kY00;  // L00 = Y00 * integral of L
  if (opt.maxLights <= 0 || !(totalLum > 0.0f) || rowPeaks.size() != std::size_t(frame.height))
    return out;
  Search search(*this, frame, rowPeaks, opt, totalLum);
  for (int n = 0; n < opt.maxLights; ++n) {
    const Search::Peak peak = search.findPeak();
    if (!(peak.value > 0.0f) || !(peak.lum > 0.0f)) break;
    const Search::Scales scales = search.scalesAt(peak);
    glm::vec3 centre = search.samples[peak.pixel].dir;
    const float coreRadius = search.measureCore(peak, scales, centre);
    if (coreRadius > glm::radians(opt.maxRadiusDeg)) break;  // not compact: no (further) light
    const float regionRadius = coreRadius + std::max(scales.glare, 0.5f * coreRadius);
    const std::optional<Rgb> fill = search.ringFill(centre, regionRadius, scales);
    if (!fill) break;  // far below the share: no light
    const bool more = n + 1 < opt.maxLights;
    const RegionSums got = search.measureRegion(centre, regionRadius, scales, *fill, more);
    if (glm::length(got.centroid) <= 0.0) break;
    const Light light = search.lightOf(got);
    if (!(light.share >= scales.minShare)) break;
    // Commit: the coefficients lose what the light took.
    for (int k = 0; k < kShCount; ++k) out.residual.c[k] -= Rgb(got.taken[k]);
    out.lights.push_back(light);
    if (more) search.fillRegion(got);
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
