// The bracket merge's row kernel, written once with Highway and compiled for each SIMD path
// (foreach_target re-includes this file once per target, inside hwy::HWY_NAMESPACE), as the
// projection's kernels are; the path is the one lp::simd names. A vector holds that many
// neighbouring pixels, and every per-pixel choice of the merge is a blend: no branch depends on a
// pixel.
#include "liveprobe/sh/simd_targets.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "merge_kernel.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
//
#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "merge_kernel.h"

HWY_BEFORE_NAMESPACE();
namespace lp::merge {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using DF = hn::ScalableTag<float>;
using VF = hn::Vec<DF>;
using MF = hn::Mask<DF>;
using DI = hn::RebindToSigned<DF>;
using DU8 = hn::Rebind<std::uint8_t, DF>;

// One frame's reading of the lanes' pixels: radiance per channel, the largest of them, the
// largest channel's code, and its weight (the hat times the exposure time).
// Pixels per block: each frame's codes go through the response a block at a time, by table
// lookups (a vector gather costs more on most x86 cores).
constexpr int kBlock = 64;

struct Reading {
  VF e0, e1, e2, peak, code, w;
  MF well;  ///< a code from wellExposed up, below the clip: compared as a ratio
};

// Per-lane sums over a row.
struct LaneSums {
  VF power, clippedPower, clippedEstimate, lostPower;
  VF best, bestClipped, bestFresh, bestX;  ///< the brightest pixel per lane, first of equals
  std::size_t dark = 0;
};

HWY_INLINE VF Luminance(DF d, VF r, VF g, VF b) {
  return hn::MulAdd(hn::Set(d, 0.0722f), b,
                    hn::MulAdd(hn::Set(d, 0.7152f), g, hn::Mul(hn::Set(d, 0.2126f), r)));
}

// What one reading says about its pixel's radiance (its largest channel), as an interval with
// room for 8-bit steps and compression noise: a mid-range code within 25%, a low code within a
// factor of two, a dark one below what would have read wellExposed, a clipped one above what
// would have read the surely-unclipped code.
struct Bounds {
  VF lo, hi;
};
HWY_INLINE Bounds BoundsOf(DF d, const RowInput& in, const Reading& r, VF s) {
  const VF floorV = hn::Set(d, float(in.floor)), clipV = hn::Set(d, float(in.clip));
  const MF dark = hn::Le(r.code, floorV), clipped = hn::Ge(r.code, clipV);
  const VF k = hn::IfThenElse(r.well, hn::Set(d, 1.25f), hn::Set(d, 2.0f));
  const VF invK = hn::IfThenElse(r.well, hn::Set(d, 0.8f), hn::Set(d, 0.5f));
  const VF lo =
      hn::IfThenElse(clipped, hn::Mul(hn::Set(d, in.belowClipLinear), s), hn::Mul(r.peak, invK));
  const VF hi = hn::IfThenElse(clipped, hn::Set(d, std::numeric_limits<float>::infinity()),
                               hn::Mul(r.peak, k));
  return {hn::IfThenZeroElse(dark, lo),
          hn::IfThenElse(dark, hn::Mul(hn::Set(d, in.wellLinear), s), hi)};
}

// `p`: the frame's bytes (B, G, R per pixel); `lin`: its codes through the response, planar
// R, G, B (kBlock floats apart).
HWY_INLINE Reading Read(DF d, const RowInput& in, const std::uint8_t* p, const float* lin,
                        float scale, float exposure) {
  const DI di;
  const DU8 du8;
  hn::Vec<DU8> b, g, r;
  hn::LoadInterleaved3(du8, p, b, g, r);
  const VF s = hn::Set(d, scale);
  Reading x;
  x.e0 = hn::Mul(hn::LoadU(d, lin), s);
  x.e1 = hn::Mul(hn::LoadU(d, lin + kBlock), s);
  x.e2 = hn::Mul(hn::LoadU(d, lin + 2 * kBlock), s);
  x.peak = hn::Max(x.e0, hn::Max(x.e1, x.e2));
  x.code = hn::ConvertTo(d, hn::PromoteTo(di, hn::Max(b, hn::Max(g, r))));
  const VF floorV = hn::Set(d, float(in.floor)), clipV = hn::Set(d, float(in.clip));
  // The hat of Debevec and Malik (0 at the noise floor and at the clip) over the radiance scale.
  const VF hat = hn::Min(hn::Sub(x.code, floorV), hn::Sub(clipV, x.code));
  x.w = hn::Mul(hn::IfThenElseZero(hn::And(hn::Gt(x.code, floorV), hn::Lt(x.code, clipV)), hat),
                hn::Set(d, exposure));
  x.well = hn::And(hn::Ge(x.code, hn::Set(d, float(in.wellExposed))), hn::Lt(x.code, clipV));
  return x;
}

// The lanes' pixels: `px[i]` the frames' bytes, `lin[i]` their linear values (Read), `valid`
// the lanes that are pixels of the row. The merged radiance goes to `rgb` (R, G, B per pixel)
// and to `planar` (R, then G kBlock floats on, then B, for the projection), each where not null.
template <int M>
void Chunk(const RowInput& in, const std::uint8_t* const* px, const float* const* lin,
           const float* previous, const float* reference, const std::uint8_t* nearLow,
           const std::uint8_t* nearHigh, float* luminance, float* rgb, float* planar, VF x,
           MF valid, LaneSums& acc) {
  const DF d;
  constexpr int m = M, now = m - 1;
  Reading r[kMaxFrames];
  for (int i = 0; i < m; ++i) r[i] = Read(d, in, px[i], lin[i], in.scale[i], 1.0f / in.scale[i]);
  const Reading& n = r[now];
  const VF sNow = hn::Set(d, in.scale[now]);
  const Bounds bNow = BoundsOf(d, in, n, sNow);
  const VF clipV = hn::Set(d, float(in.clip));
  // Where an older reading contradicts the newest, the newest wins: the older one's weight goes,
  // and the largest such radiance is what was lost (-1: nothing). Where both are well exposed
  // and agree, the older one is weighed by how closely (d = log q, to within 2%).
  VF lost = hn::Set(d, -1.0f);
  // Turned frames: the newest frame's neighbourhood bounds what a reading a fraction of a pixel
  // off may say (green's response for the neighbours' largest channel).
  const bool turned = nearLow != nullptr;
  Bounds wide = bNow;
  MF edge = hn::FirstN(d, 0);
  if (turned) {
    const DI di;
    const auto neighbour = [&](const std::uint8_t* codes) HWY_ATTR {
      Reading q;
      const auto index = hn::PromoteTo(di, hn::LoadU(DU8(), codes));
      q.code = hn::ConvertTo(d, index);
      q.peak = hn::Mul(hn::GatherIndex(d, in.lut[1], index), sNow);
      q.well = hn::And(hn::Ge(q.code, hn::Set(d, float(in.wellExposed))), hn::Lt(q.code, clipV));
      return q;
    };
    const Reading low = neighbour(nearLow), high = neighbour(nearHigh);
    wide.lo = hn::Min(wide.lo, BoundsOf(d, in, low, sNow).lo);
    wide.hi = hn::Max(wide.hi, BoundsOf(d, in, high, sNow).hi);
    edge = hn::Ge(high.code, clipV);
  }
  MF newestGivesWay = hn::FirstN(d, 0);
  for (int i = 0; i < now; ++i) {
    Reading& o = r[i];
    const MF both = hn::And(o.well, n.well);
    // Beside the newest frame's clipped core, a shorter exposure reading brighter: the source's
    // edge, not a contradiction.
    const MF edgeOfSource =
        in.scale[i] > 1.02f * in.scale[now]
            ? hn::And(edge, hn::And(both, hn::Gt(o.peak, hn::Mul(hn::Set(d, 1.5625f), n.peak))))
            : hn::FirstN(d, 0);
    newestGivesWay = hn::Or(newestGivesWay, edgeOfSource);
    // q = o / n within (1 / 1.5625, 1.5625); n > 0 where it is well exposed.
    // q = o / n within (1 / 1.5625, 1.5625); n > 0 where it is well exposed. Turned: the
    // readings' intervals meet those of the newest's neighbourhood (for two well-exposed
    // readings, the same tolerance).
    const Bounds b = BoundsOf(d, in, o, hn::Set(d, in.scale[i]));
    const MF apart = hn::Or(hn::Gt(b.lo, wide.hi), hn::Gt(wide.lo, b.hi));
    const MF agree =
        turned ? hn::AndNot(apart, both)
               : hn::And(both, hn::And(hn::Lt(o.peak, hn::Mul(hn::Set(d, 1.25f * 1.25f), n.peak)),
                                       hn::Gt(hn::Mul(hn::Set(d, 1.25f * 1.25f), o.peak), n.peak)));
    const MF disagree = hn::AndNot(
        edgeOfSource, turned ? apart : hn::Or(hn::AndNot(agree, both), hn::AndNot(both, apart)));
    const VF dq =
        hn::Div(hn::Mul(hn::Set(d, 2.0f), hn::Sub(o.peak, n.peak)), hn::Add(o.peak, n.peak));
    const VF closeness = hn::Exp(d, hn::Neg(hn::Mul(hn::Mul(dq, dq), hn::Set(d, in.inv2s2))));
    o.w = hn::IfThenZeroElse(disagree, hn::IfThenElse(agree, hn::Mul(o.w, closeness), o.w));
    lost = hn::IfThenElse(disagree, hn::Max(lost, Luminance(d, o.e0, o.e1, o.e2)), lost);
  }
  r[now].w = hn::IfThenZeroElse(newestGivesWay, r[now].w);
  // Two older readings, both well exposed, where the shorter exposure reads brighter beyond the
  // tolerance: the edge of a source the longer one clips, the two placed a fraction of a pixel
  // apart (the turn between them, resampled) or the source moved. The longer reading misses
  // light the shorter one measured beside the clipped core, and gives way.
  for (int i = 0; i < now; ++i)
    for (int j = 0; j < now; ++j) {
      if (j == i || !(in.scale[j] > 1.02f * in.scale[i])) continue;  // j: the shorter exposure
      const MF brighter =
          hn::And(hn::And(r[i].well, hn::Gt(r[j].w, hn::Zero(d))),
                  hn::And(r[j].well, hn::Gt(r[j].peak, hn::Mul(hn::Set(d, 1.5625f), r[i].peak))));
      r[i].w = hn::IfThenZeroElse(brighter, r[i].w);
    }
  // The weighted mean; the clipped reading that bounds the pixel highest (the first of equals).
  VF sw = hn::Zero(d), c0 = sw, c1 = sw, c2 = sw;
  VF k0 = sw, k1 = sw, k2 = sw, kPeak = hn::Set(d, -1.0f);
  MF wellSeen = hn::FirstN(d, 0), hasClip = wellSeen;
  for (int i = 0; i < m; ++i) {
    const Reading& o = r[i];
    sw = hn::Add(sw, o.w);
    wellSeen = hn::Or(wellSeen, hn::And(hn::Gt(o.w, hn::Zero(d)), o.well));
    c0 = hn::MulAdd(o.w, o.e0, c0), c1 = hn::MulAdd(o.w, o.e1, c1), c2 = hn::MulAdd(o.w, o.e2, c2);
    const MF higher = hn::And(hn::Ge(o.code, clipV), hn::Gt(o.peak, kPeak));
    hasClip = hn::Or(hasClip, higher);
    kPeak = hn::IfThenElse(higher, o.peak, kPeak);
    k0 = hn::IfThenElse(higher, o.e0, k0), k1 = hn::IfThenElse(higher, o.e1, k1);
    k2 = hn::IfThenElse(higher, o.e2, k2);
  }
  // Unmeasured. Contradicted: as the newest frame reads it. Clipped somewhere: at least the
  // highest bound a clipped reading sets. Dark everywhere: the longest exposure's.
  const MF measured = hn::Gt(sw, hn::Zero(d));
  const MF contradicted = hn::Ge(lost, hn::Zero(d));
  const Reading& lg = r[in.longest];
  const VF inv = hn::Div(hn::Set(d, 1.0f), sw);
  const auto pick = [&](VF mean, VF eNow, VF eClip, VF eLong) HWY_ATTR {
    return hn::IfThenElse(
        measured, hn::Mul(mean, inv),
        hn::IfThenElse(contradicted, eNow, hn::IfThenElse(hasClip, eClip, eLong)));
  };
  c0 = pick(c0, n.e0, k0, lg.e0), c1 = pick(c1, n.e1, k1, lg.e1), c2 = pick(c2, n.e2, k2, lg.e2);
  const MF clipped = hn::AndNot(measured, hn::Or(hn::And(contradicted, hn::Ge(n.code, clipV)),
                                                 hn::AndNot(contradicted, hasClip)));
  if (rgb) hn::StoreInterleaved3(c0, c1, c2, d, rgb);
  if (planar) {
    hn::Store(c0, d, planar), hn::Store(c1, d, planar + kBlock);
    hn::Store(c2, d, planar + 2 * kBlock);
  }

  // The row's sums. What was lost: at least what the older readings say, and what the last merge
  // saw where the newest frame (turned: its neighbourhood) rules that out.
  const VF l = Luminance(d, c0, c1, c2);
  const VF seen = in.fresh ? hn::LoadU(d, previous) : hn::Zero(d);  // read before it is written
  hn::StoreU(l, d, luminance);
  const MF gone =
      hn::And(valid, hn::Or(contradicted, hn::Gt(seen, hn::Mul(hn::Set(d, 1.25f), wide.hi))));
  acc.lostPower =
      hn::Add(acc.lostPower,
              hn::IfThenElseZero(gone, hn::Max(hn::Sub(hn::Max(lost, seen), l), hn::Zero(d))));
  acc.power = hn::Add(acc.power, hn::IfThenElseZero(valid, l));
  const MF clippedHere = hn::And(valid, clipped);
  acc.clippedPower = hn::Add(acc.clippedPower, hn::IfThenElseZero(clippedHere, l));
  acc.clippedEstimate = hn::Add(
      acc.clippedEstimate, hn::IfThenElseZero(clippedHere, hn::Max(l, hn::LoadU(d, reference))));
  acc.dark += hn::CountTrue(d, hn::AndNot(hn::Or(clipped, wellSeen), valid));
  const MF up = hn::And(valid, hn::Gt(l, acc.best));
  const VF one = hn::Set(d, 1.0f);
  acc.best = hn::IfThenElse(up, l, acc.best);
  acc.bestClipped = hn::IfThenElse(up, hn::IfThenElseZero(clipped, one), acc.bestClipped);
  acc.bestFresh =
      hn::IfThenElse(up, hn::IfThenElseZero(hn::Gt(n.w, hn::Zero(d)), one), acc.bestFresh);
  acc.bestX = hn::IfThenElse(up, x, acc.bestX);
}

RowSums MergeRow(const RowInput& in) {
  const DF d;
  const int lanes = int(hn::Lanes(d));
  LaneSums acc;
  acc.power = acc.clippedPower = acc.clippedEstimate = acc.lostPower = hn::Zero(d);
  acc.best = hn::Set(d, -1.0f);
  acc.bestClipped = acc.bestFresh = acc.bestX = hn::Zero(d);
  const VF iota = hn::Iota(d, 0.0f);
  HWY_ALIGN std::uint8_t bytes[kMaxFrames][3 * kBlock];
  HWY_ALIGN float linear[kMaxFrames][3 * kBlock];
  HWY_ALIGN float prev[kBlock], ref[kBlock], lum[kBlock], out[3 * kBlock];
  HWY_ALIGN std::uint8_t low[kBlock], high[kBlock];
  const std::uint8_t* px[kMaxFrames];
  const float* lin[kMaxFrames];
  const float *lutR = in.lut[0], *lutG = in.lut[1], *lutB = in.lut[2];
  // One chunk function per frame count, its loops over the frames unrolled.
  constexpr decltype(&Chunk<1>) kChunks[kMaxFrames] = {&Chunk<1>, &Chunk<2>, &Chunk<3>, &Chunk<4>,
                                                       &Chunk<5>};
  const auto chunk = kChunks[std::clamp(in.frames, 1, kMaxFrames) - 1];
  // The projection as the row merges: the radiance of each block, still in L1, weighed by the
  // column integrals (as the projector's equirect kernel does), s[k][c] column sum k of channel c.
  const bool project = in.col[0] != nullptr;
  VF s[5][3];
  for (auto& sk : s)
    for (VF& v : sk) v = hn::Zero(d);
  VF peak = hn::Zero(d);  // the largest channel value (merged radiance is never negative)
  HWY_ALIGN float colTail[5][kBlock];
  HWY_ALIGN float radiance[3 * kBlock];  // the block's merged radiance, planar
  for (int x0 = 0; x0 < in.width; x0 += kBlock) {
    const int count = std::min(kBlock, in.width - x0);
    // The last pixels of a row go through zero-padded copies.
    const bool whole = count == kBlock;
    for (int i = 0; i < in.frames; ++i) {
      const std::uint8_t* src = in.bgr[i] + 3 * x0;
      if (!whole) {
        std::memset(bytes[i], 0, sizeof bytes[i]);
        std::memcpy(bytes[i], src, std::size_t(3 * count));
        src = bytes[i];
      }
      px[i] = src;
      float* l = linear[i];
      lin[i] = l;
      for (int k = 0; k < kBlock; ++k) {
        l[k] = lutR[src[3 * k + 2]];
        l[kBlock + k] = lutG[src[3 * k + 1]];
        l[2 * kBlock + k] = lutB[src[3 * k]];
      }
    }
    const float* previous = in.previous + x0;
    const float* reference = in.reference + x0;
    const std::uint8_t* nearLow = in.nearLow ? in.nearLow + x0 : nullptr;
    const std::uint8_t* nearHigh = in.nearHigh ? in.nearHigh + x0 : nullptr;
    float* luminance = in.luminance + x0;
    float* rgb = in.rgb ? in.rgb + 3 * x0 : nullptr;
    if (!whole) {
      std::fill(prev, prev + kBlock, 0.0f), std::fill(ref, ref + kBlock, 0.0f);
      std::memcpy(prev, previous, sizeof(float) * std::size_t(count));
      std::memcpy(ref, reference, sizeof(float) * std::size_t(count));
      previous = prev, reference = ref, luminance = lum;
      if (rgb) rgb = out;
      if (nearLow) {
        std::memset(low, 0, sizeof low), std::memset(high, 0, sizeof high);
        std::memcpy(low, nearLow, std::size_t(count)),
            std::memcpy(high, nearHigh, std::size_t(count));
        nearLow = low, nearHigh = high;
      }
    }
    for (int x = 0; x < kBlock; x += lanes) {
      const std::uint8_t* pxAt[kMaxFrames];
      const float* linAt[kMaxFrames];
      for (int i = 0; i < in.frames; ++i) pxAt[i] = px[i] + 3 * x, linAt[i] = lin[i] + x;
      chunk(in, pxAt, linAt, previous + x, reference + x, nearLow ? nearLow + x : nullptr,
            nearHigh ? nearHigh + x : nullptr, luminance + x, rgb ? rgb + 3 * x : nullptr,
            project ? radiance + x : nullptr, hn::Add(iota, hn::Set(d, float(x0 + x))),
            hn::FirstN(d, std::size_t(std::clamp(count - x, 0, lanes))), acc);
    }
    if (project) {
      const float* col[5];
      for (int k = 0; k < 5; ++k) {
        col[k] = in.col[k] + x0;
        if (!whole) {
          std::fill(colTail[k], colTail[k] + kBlock, 0.0f);
          std::memcpy(colTail[k], col[k], sizeof(float) * std::size_t(count));
          col[k] = colTail[k];
        }
      }
      for (int x = 0; x < kBlock; x += lanes) {
        const VF r = hn::Load(d, radiance + x), g = hn::Load(d, radiance + kBlock + x),
                 b = hn::Load(d, radiance + 2 * kBlock + x);
        const MF valid = hn::FirstN(d, std::size_t(std::clamp(count - x, 0, lanes)));
        peak = hn::Max(peak, hn::IfThenElseZero(valid, hn::Max(r, hn::Max(g, b))));
        for (int k = 0; k < 5; ++k) {
          const VF wk = hn::LoadU(d, col[k] + x);
          s[k][0] = hn::MulAdd(wk, r, s[k][0]), s[k][1] = hn::MulAdd(wk, g, s[k][1]);
          s[k][2] = hn::MulAdd(wk, b, s[k][2]);
        }
      }
    }
    if (!whole) {
      std::memcpy(in.luminance + x0, lum, sizeof(float) * std::size_t(count));
      if (in.rgb) std::memcpy(in.rgb + 3 * x0, out, sizeof(float) * std::size_t(3 * count));
    }
  }
  // The lanes, summed in double; the brightest is the first pixel of the largest luminance.
  HWY_ALIGN float v[8][64];
  const VF all[8] = {acc.power, acc.clippedPower, acc.clippedEstimate, acc.lostPower,
                     acc.best,  acc.bestClipped,  acc.bestFresh,       acc.bestX};
  for (int k = 0; k < 8; ++k) hn::Store(all[k], d, v[k]);
  RowSums sums;
  sums.dark = acc.dark;
  float firstX = 0;
  for (int j = 0; j < lanes; ++j) {
    sums.power += v[0][j], sums.clippedPower += v[1][j], sums.clippedEstimate += v[2][j];
    sums.lostPower += v[3][j];
    if (v[4][j] > sums.brightest || (v[4][j] == sums.brightest && v[7][j] < firstX))
      sums.brightest = v[4][j], sums.brightestClipped = v[5][j] > 0,
      sums.brightestFresh = v[6][j] > 0, firstX = v[7][j];
  }
  if (project) {
    for (int k = 0; k < 5; ++k)
      for (int c = 0; c < 3; ++c) {
        hn::Store(s[k][c], d, v[0]);
        for (int j = 0; j < lanes; ++j) sums.col[k][c] += double(v[0][j]);
      }
    sums.peak = hn::GetLane(hn::MaxOfLanes(d, peak));
  }
  return sums;
}

}  // namespace HWY_NAMESPACE
}  // namespace lp::merge
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <string>

#include "liveprobe/sh/simd.h"

namespace lp::merge {

RowInput RowInput::of(const FrameInput& frame, std::size_t y) {
  RowInput in;
  static_cast<FrameInput&>(in) = frame;
  const std::size_t at = y * std::size_t(frame.width);
  for (int i = 0; i < frame.frames; ++i) in.bgr[i] = frame.bgr[i] + 3 * at;
  in.previous = frame.previous + at, in.luminance = frame.luminance + at;
  in.reference = frame.reference + at;
  if (frame.nearLow) in.nearLow = frame.nearLow + at, in.nearHigh = frame.nearHigh + at;
  if (frame.rgb) in.rgb = frame.rgb + 3 * at;
  return in;
}

RowKernel active() {
  const std::string path = lp::simd::current();
#if HWY_TARGETS & HWY_AVX3
  if (path == "avx512") return &N_AVX3::MergeRow;
#endif
#if HWY_TARGETS & HWY_AVX2
  if (path == "avx2") return &N_AVX2::MergeRow;
#endif
#if HWY_TARGETS & HWY_NEON
  if (path == "neon") return &N_NEON::MergeRow;
#endif
#if HWY_TARGETS & HWY_EMU128
  return &N_EMU128::MergeRow;
#else
  return &N_SCALAR::MergeRow;
#endif
}

}  // namespace lp::merge
#endif  // HWY_ONCE
