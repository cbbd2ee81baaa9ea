#include "liveprobe/sh/projector.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <optional>

#include "liveprobe/sh/error.h"
#include "project_kernel.h"
#include "unseen.h"

namespace lp {

namespace {

// Exact pixel integrals for the equirect layout. With u = cos t, each basis function is
// Y = K g(t) f(p), and the integral over a pixel is K (int g(t) sin t dt)(int f(p) dp):
//   g: 1, cos t, sin t, sin t cos t, sin^2 t, 3 cos^2 t - 1
//   int_{t0}^{t1} g sin t dt = int_{u1}^{u0} g du:
//     1 -> u0 - u1;  cos -> (u0^2 - u1^2)/2;  3u^2-1 -> (u0^3 - u0) - (u1^3 - u1);
//     sin^2 -> (u0 - u0^3/3) - (u1 - u1^3/3);  sin -> [t/2 - sin 2t/4]_{t0}^{t1};
//     sin cos -> [sin^3 t / 3]_{t0}^{t1}
//   f: 1, cos p, sin p, cos 2p, sin 2p with the obvious antiderivatives.
// Basis in these factors: Y00 = k0; Y1-1 = k1 sin t sin p; Y10 = k1 cos t; Y11 = k1 sin t cos p;
// Y2-2 = (k2/2) sin^2 t sin 2p; Y2-1 = k2 sin t cos t sin p; Y20 = k3 (3cos^2 t - 1);
// Y21 = k2 sin t cos t cos p; Y22 = k4 sin^2 t cos 2p.
kernel::EquirectTables equirectTables(int width, int height) {
  const double pi = kPi;
  constexpr double k0 = kY00, k1 = kY1, k2 = kY2, k3 = kY20, k4 = kY22;
  kernel::EquirectTables tables;
  auto* t = &tables;
  t->width = width;
  t->height = height;
  const std::size_t padded = (std::size_t(width) + 15) / 16 * 16;
  for (auto& c : t->col) c.assign(padded, 0.0f);
  for (int j = 0; j < width; ++j) {
    const double p0 = 2 * pi * j / width, p1 = 2 * pi * (j + 1) / width;
    t->col[0][j] = float(p1 - p0);
    t->col[1][j] = float(std::sin(p1) - std::sin(p0));
    t->col[2][j] = float(std::cos(p0) - std::cos(p1));
    t->col[3][j] = float((std::sin(2 * p1) - std::sin(2 * p0)) / 2);
    t->col[4][j] = float((std::cos(2 * p0) - std::cos(2 * p1)) / 2);
  }
  // Row factors with the basis constants folded in (slots as EquirectIntegrals::kRowOf uses them).
  for (auto& r : t->row) r.resize(std::size_t(height));
  for (int i = 0; i < height; ++i) {
    const double t0 = pi * i / height, t1 = pi * (i + 1) / height;
    const double u0 = std::cos(t0), u1 = std::cos(t1);
    const double one = u0 - u1;
    const double cosT = (u0 * u0 - u1 * u1) / 2;
    const double sinT = (t1 / 2 - std::sin(2 * t1) / 4) - (t0 / 2 - std::sin(2 * t0) / 4);
    const double sinCos = (std::pow(std::sin(t1), 3) - std::pow(std::sin(t0), 3)) / 3;
    const double sin2 = (u0 - u0 * u0 * u0 / 3) - (u1 - u1 * u1 * u1 / 3);
    const double threeCos2 = (u0 * u0 * u0 - u0) - (u1 * u1 * u1 - u1);
    // Each coefficient k uses one row factor; the kernel multiplies it by one column sum:
    // L00 = k0 R1 S1; L1-1 = k1 Rs Ssin; L10 = k1 Rc S1; L11 = k1 Rs Scos; L2-2 = k2/2 Rs2 Ssin2;
    // L2-1 = k2 Rsc Ssin; L20 = k3 R3 S1; L21 = k2 Rsc Scos; L22 = k4 Rs2 Scos2.
    // Row factor slots (EquirectIntegrals::kRowOf): 0 k0*one, 1 k1*cosT, 2 k1*sinT, 3 k2*sinCos,
    // 4 sin2 (times k2/2 for L2-2 or k4 for L22: equal, since k2/2 = k4), 5 k3*threeCos2.
    t->row[0][i] = float(k0 * one);
    t->row[1][i] = float(k1 * cosT);
    t->row[2][i] = float(k1 * sinT);
    t->row[3][i] = float(k2 * sinCos);
    t->row[4][i] = float(k4 * sin2);
    t->row[5][i] = float(k3 * threeCos2);
  }
  return tables;
}

/// Sample layouts: q = sqrt(dw) and q dir per pixel, as kernel::SampleStreams, each padded with
/// a vector of zeros.
std::array<std::vector<float>, 4> sampleStreams(const std::vector<SphereSample>& samples) {
  std::array<std::vector<float>, 4> out;
  for (auto& s : out) s.assign(samples.size() + kernel::kMaxLanes, 0);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const float q = std::sqrt(samples[i].solidAngle);
    out[0][i] = q;
    out[1][i] = q * samples[i].dir.x;
    out[2][i] = q * samples[i].dir.y;
    out[3][i] = q * samples[i].dir.z;
  }
  return out;
}

using Sums = std::array<double, 27>;

Sh9 toSh9(const Sums& s, bool bgr) {
  Sh9 out;
  for (int k = 0; k < kShCount; ++k)
    out.c[k] = bgr ? Rgb(float(s[3 * k + 2]), float(s[3 * k + 1]), float(s[3 * k]))
                   : Rgb(float(s[3 * k]), float(s[3 * k + 1]), float(s[3 * k + 2]));
  return out;
}

template <std::size_t N>
void addSums(std::array<double, N>& into, const std::array<double, N>& part) {
  for (std::size_t q = 0; q < N; ++q) into[q] += part[q];
}

/// Rows of any format as linear RGB (or BGR) floats: a pointer into the frame for f32, a
/// per-task buffer for the others.
class RowReader {
 public:
  RowReader(const PanoramaView& v, const kernel::Kernels& k) : v_(v), k_(k) {}
  /// `count` pixels starting at pixel `first` of row `row`.
  const float* read(int row, std::size_t first, std::size_t count) {
    const auto* base =
        static_cast<const std::uint8_t*>(v_.data) + std::size_t(row) * v_.strideBytes();
    const std::size_t n = 3 * count;
    switch (v_.format) {
      case PanoramaFormat::RgbF32:
        return reinterpret_cast<const float*>(base) + 3 * first;
      case PanoramaFormat::RgbF16:
        buf_.resize(n);
        k_.decodeF16(reinterpret_cast<const std::uint16_t*>(base) + 3 * first, buf_.data(), n);
        return buf_.data();
      case PanoramaFormat::BgrU8:
      case PanoramaFormat::RgbU8:
        buf_.resize(n);
        k_.decodeU8(base + 3 * first, v_.decode, buf_.data(), n);
        return buf_.data();
    }
    return nullptr;
  }

 private:
  const PanoramaView& v_;
  const kernel::Kernels& k_;
  std::vector<float> buf_;
};

bool packed(const PanoramaView& v) { return v.strideBytes() == v.bytesPerPixel() * v.width; }

}  // namespace

std::size_t PanoramaView::bytesPerPixel() const {
  switch (format) {
    case PanoramaFormat::RgbF32:
      return 12;
    case PanoramaFormat::RgbF16:
      return 6;
    case PanoramaFormat::BgrU8:
    case PanoramaFormat::RgbU8:
      return 3;
  }
  return 0;
}

struct Projector::Tables {
  std::optional<kernel::EquirectTables> equirect;
  std::array<std::vector<float>, 4> streams;  ///< sample layouts: kernel::SampleStreams
  unseen::Fill fill;                          ///< sample layouts: what fills the unseen
  std::vector<char> blockUsed;  ///< per block of 16 pixels: any weight non-zero (in the image)
  mutable std::once_flag weightsOnce;
  mutable std::vector<float> weights;  ///< blockedWeights(), made when first asked

  kernel::SampleStreams streamsAt(std::size_t pixel) const {
    return {streams[0].data() + pixel, streams[1].data() + pixel, streams[2].data() + pixel,
            streams[3].data() + pixel};
  }
};

Projector::Projector(const LayoutSpec& spec, int width, int height)
    : spec_(spec), width_(width), height_(height), samples_(layoutSamples(spec, width, height)) {
  auto t = std::make_unique<Tables>();
  coverage_ = unseen::coverage(samples_);
  if (spec.layout == Layout::Equirect) {
    t->equirect = equirectTables(width, height);
  } else {
    t->streams = sampleStreams(samples_);
    t->fill = unseen::fill(spec, width, height, samples_);
  }
  t->blockUsed.assign((samples_.size() + 15) / 16, 0);
  for (std::size_t i = 0; i < samples_.size(); ++i)
    if (samples_[i].solidAngle != 0.0f) t->blockUsed[i / 16] = 1;
  tables_ = std::move(t);
}

std::array<float, kShCount> Projector::pixelWeights(std::size_t p) const {
  const SphereSample& s = samples_[p];
  auto w = tables_->fill.at(p, s);
  if (s.solidAngle == 0.0f) return w;
  const auto y = shBasis(s.dir);
  for (int k = 0; k < kShCount; ++k) w[k] += y[k] * s.solidAngle;
  return w;
}

const EquirectIntegrals* Projector::equirectIntegrals() const {
  return tables_->equirect ? &*tables_->equirect : nullptr;
}

const std::vector<float>& Projector::blockedWeights() const {
  const Tables& t = *tables_;
  std::call_once(t.weightsOnce, [&] {
    if (t.equirect) return;
    t.weights.assign((samples_.size() + 15) / 16 * 16 * kShCount, 0.0f);
    for (std::size_t p = 0; p < samples_.size(); ++p) {
      const auto w = pixelWeights(p);
      for (int k = 0; k < kShCount; ++k) t.weights[((p / 16) * kShCount + k) * 16 + p % 16] = w[k];
    }
  });
  return t.weights;
}

Projector::~Projector() = default;
Projector::Projector(Projector&&) noexcept = default;
Projector& Projector::operator=(Projector&&) noexcept = default;

void Projector::check(const PanoramaView& v) const {
  if (v.width != width_ || v.height != height_ || v.layout.layout != spec_.layout)
    throw Error("projection: a " + std::to_string(v.width) + "x" + std::to_string(v.height) + " " +
                std::string(layoutName(v.layout.layout)) + " frame given to a projector for " +
                std::to_string(width_) + "x" + std::to_string(height_) + " " +
                std::string(layoutName(spec_.layout)));
  const bool u8 = v.format == PanoramaFormat::BgrU8 || v.format == PanoramaFormat::RgbU8;
  if (u8 && !v.decode) throw Error("projection: an 8-bit frame needs its decode table");
  if (!v.data) throw Error("projection: the frame has no pixels");
}

Sh9 Projector::project(const PanoramaView& v, Executor* ex, std::vector<float>* rowPeaks) const {
  check(v);
  const bool bgr = v.format == PanoramaFormat::BgrU8;
  if (rowPeaks) rowPeaks->assign(std::size_t(height_), 0.0f);
  if (tables_->equirect) return toSh9(equirectSums(v, ex, rowPeaks), bgr);
  if (rowPeaks) {
    const kernel::Kernels& k = kernel::active();
    parallelFor(ex, std::size_t(height_), Split{16}, [&](std::size_t r0, std::size_t r1) {
      RowReader rows(v, k);
      for (std::size_t i = r0; i < r1; ++i)
        (*rowPeaks)[i] =
            k.maxOf(rows.read(int(i), 0, std::size_t(width_)), 3 * std::size_t(width_));
    });
  }
  return toSh9(sampleSums(v, ex), bgr);
}

void Projector::addPixels(std::size_t row, std::size_t col, const Rgb* values, std::size_t count,
                          std::array<glm::dvec3, kShCount>& sums) const {
  // Float over the run (at most a row, as project() sums), double beyond.
  if (tables_->equirect) {
    // The five column sums first, then the row integrals.
    const auto& t = *tables_->equirect;
    Rgb colSums[5]{};
    for (std::size_t n = 0; n < count; ++n)
      for (int c = 0; c < 5; ++c) colSums[c] += values[n] * t.col[c][col + n];
    t.addRow(row, colSums, sums);
    return;
  }
  const std::size_t first = row * std::size_t(width_) + col;
  std::array<Rgb, kShCount> runSums{};
  for (std::size_t n = 0; n < count; ++n) {
    const auto w = pixelWeights(first + n);
    for (int k = 0; k < kShCount; ++k) runSums[k] += values[n] * w[k];
  }
  for (int k = 0; k < kShCount; ++k) sums[k] += glm::dvec3(runSums[k]);
}

// Equirect: bands of whole rows (at least 32 each); per row, the kernel's 15 column sums times
// the row factors go into float lanes, flushed to double every 64 rows (in the frame's channel
// order).
std::array<double, 27> Projector::equirectSums(const PanoramaView& v, Executor* ex,
                                               std::vector<float>* rowPeaks) const {
  const auto& t = *tables_->equirect;
  const kernel::Kernels& k = kernel::active();
  const auto band = [&](std::size_t r0, std::size_t r1) {
    constexpr std::size_t kFlushRows = 64;
    RowReader rows(v, k);
    kernel::LaneSums lanes{};
    Sums sums{};
    auto flush = [&] {
      for (int q = 0; q < 27; ++q) {
        double s = 0;
        for (int l = 0; l < kernel::kMaxLanes; ++l) s += lanes.v[q * kernel::kMaxLanes + l];
        sums[q] += s;
      }
      lanes = {};
    };
    for (std::size_t i = r0; i < r1; ++i) {
      const float* row = rows.read(int(i), 0, std::size_t(width_));
      k.equirectRow(t, row, int(i), lanes, rowPeaks ? &(*rowPeaks)[i] : nullptr);
      if ((i - r0 + 1) % kFlushRows == 0) flush();
    }
    flush();
    return sums;
  };
  return parallelReduce(ex, std::size_t(height_), Split{32}, Sums{}, band, addSums<27>);
}

// Other layouts: runs of pixels through the products of their streams (the frame's channel
// order), skipping blocks of 16 wholly outside the layout's disc or circles (a fifth of an
// angular map); then the basis constants, the ground's share of the cosine sums, and the edge
// pixels' fill.
std::array<double, 27> Projector::sampleSums(const PanoramaView& v, Executor* ex) const {
  const kernel::Kernels& k = kernel::active();
  const Tables& t = *tables_;
  const std::size_t w = std::size_t(width_);
  const float up[3] = {t.fill.up.x, t.fill.up.y, t.fill.up.z};
  using Products = std::array<double, 3 * kernel::kProducts>;
  const auto run = [&](std::size_t i0, std::size_t i1) {
    RowReader rows(v, k);
    Products sums{};
    // All of a packed frame's run at once; a strided one row by row.
    for (std::size_t i = i0; i < i1;) {
      const std::size_t end = packed(v) ? i1 : std::min(i1, (i / w + 1) * w);
      for (std::size_t b = i; b < end;) {
        if (!t.blockUsed[b / 16]) {
          b = std::min(end, (b / 16 + 1) * 16);
          continue;
        }
        std::size_t e = b;
        while (e < end && t.blockUsed[e / 16]) e = std::min(end, (e / 16 + 1) * 16);
        const float* px = rows.read(int(b / w), b % w, e - b);
        k.sampleSums(px, e - b, t.streamsAt(b), up, sums.data());
        b = e;
      }
      i = end;
    }
    return sums;
  };
  const Products p = parallelReduce(ex, samples_.size(), Split{16384}, Products{}, run,
                                    addSums<Products{}.size()>);
  Sums out{};
  const double c[9] = {kY00, kY1, kY1, kY1, kY2, kY2, kY20, kY2, kY22};
  for (int j = 0; j < kShCount; ++j)
    for (int ch = 0; ch < 3; ++ch) {
      double s = c[j] * p[3 * j + ch];
      if (t.fill.hasGround) s += double(t.fill.ground[j]) * p[3 * 9 + ch];
      out[3 * j + ch] = s;
    }
  // Edge pixels in the frame's channel order, as the sums (readPixel gives R, G, B).
  const bool bgr = v.format == PanoramaFormat::BgrU8;
  for (std::size_t e = 0; e < t.fill.pixels.size(); ++e) {
    const Rgb px = readPixel(v, t.fill.pixels[e]);
    const double ch[3] = {bgr ? px.b : px.r, px.g, bgr ? px.r : px.b};
    for (int j = 0; j < kShCount; ++j)
      for (int q = 0; q < 3; ++q) out[3 * j + q] += double(t.fill.weights[e][j]) * ch[q];
  }
  return out;
}

namespace {
// IEEE binary16 to float, scalar (the kernels convert whole rows; this reads single pixels).
float halfToFloat(std::uint16_t h) {
  const std::uint32_t sign = std::uint32_t(h & 0x8000u) << 16, exp = (h >> 10) & 0x1fu,
                      man = h & 0x3ffu;
  float v;
  if (exp == 0)
    v = std::ldexp(float(man), -24);  // zero or subnormal
  else if (exp == 31)
    v = man ? NAN : INFINITY;
  else
    v = std::ldexp(float(man | 0x400u), int(exp) - 25);
  return sign ? -v : v;
}
}  // namespace

void readPixels(const PanoramaView& v, std::size_t row, std::size_t col, std::size_t count,
                Rgb* out) {
  const auto* base = static_cast<const std::uint8_t*>(v.data) + row * v.strideBytes();
  switch (v.format) {
    case PanoramaFormat::RgbF32: {
      const float* p = reinterpret_cast<const float*>(base) + 3 * col;
      for (std::size_t n = 0; n < count; ++n, p += 3) out[n] = {p[0], p[1], p[2]};
      return;
    }
    case PanoramaFormat::RgbF16: {
      const auto* p = reinterpret_cast<const std::uint16_t*>(base) + 3 * col;
      for (std::size_t n = 0; n < count; ++n, p += 3)
        out[n] = {halfToFloat(p[0]), halfToFloat(p[1]), halfToFloat(p[2])};
      return;
    }
    case PanoramaFormat::BgrU8: {
      const std::uint8_t* p = base + 3 * col;
      for (std::size_t n = 0; n < count; ++n, p += 3)
        out[n] = {v.decode[p[2]], v.decode[p[1]], v.decode[p[0]]};
      return;
    }
    case PanoramaFormat::RgbU8: {
      const std::uint8_t* p = base + 3 * col;
      for (std::size_t n = 0; n < count; ++n, p += 3)
        out[n] = {v.decode[p[0]], v.decode[p[1]], v.decode[p[2]]};
      return;
    }
  }
}

Rgb readPixel(const PanoramaView& v, std::size_t index) {
  Rgb out;
  readPixels(v, index / std::size_t(v.width), index % std::size_t(v.width), 1, &out);
  return out;
}

Sh9 project(const PanoramaView& frame, Executor* executor) {
  return Projector(frame.layout, frame.width, frame.height).project(frame, executor);
}

}  // namespace lp
