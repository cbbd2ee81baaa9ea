#include "liveprobe/gl/gpu_merge.h"

#include <algorithm>
#include <string>

#include "liveprobe/gl/context.h"
#include "liveprobe/gl/gpu_projector.h"
#include "programs.h"

namespace lp::gl {

namespace {

enum Binding {
  kFrames,
  kLut,
  kPrevious,
  kReference,
  kLuminance,
  kNear,
  kRgb,
  kCol,
  kRows,
  kRecode,
  kNodes,
  kBindings
};
// Frame slots: the window's frames as taken, and as many turned to the newest.
constexpr int kSlots = 2 * merge::kMaxFrames;

// Floats a row's sums take in the Rows buffer: power, clipped power, clipped estimate, lost
// power, dark pixels, the brightest luminance, its clipped and fresh flags, its column, the
// 15 column-weighted sums, and the largest channel value.
constexpr int kRowFloats = 25;

// A workgroup a row, or a part of one (`parts` a row); each of its GROUP invocations merges every
// GROUP-th pixel of it as the CPU's row kernel (hdr/src/merge_kernel.cpp, Chunk) merges a lane,
// then the part's sums are halved down in shared memory, and the CPU adds a row's parts. Bytes are
// read from 32-bit words (GLSL has no 8-bit storage in 4.3); the response from shared memory. GROUP
// (the invocations of a workgroup) and JUDGE (0: no contradictions judged, a bound for measuring)
// are defined before it (GpuMergeShape).
const char* const kMergeCs = R"(
layout(local_size_x = GROUP) in;
layout(std430, binding = 0) readonly buffer Frames { uint frameWords[]; };
layout(std430, binding = 1) readonly buffer Lut { float lut[]; };
layout(std430, binding = 2) readonly buffer Previous { float previous[]; };
layout(std430, binding = 3) readonly buffer Reference { float reference[]; };
layout(std430, binding = 4) writeonly buffer Luminance { float luminance[]; };
layout(std430, binding = 5) readonly buffer Near { uint nearWords[]; };
layout(std430, binding = 6) writeonly buffer Rgb { float rgb[]; };
layout(std430, binding = 7) readonly buffer Col { float col[]; };
layout(std430, binding = 8) writeonly buffer Rows { float rows[]; };
uniform int width, frames, longest, floorCode, clipCode, wellCode;
uniform float wellLinear, belowClipLinear, inv2s2;
uniform int fresh, turned, writeRgb, project, parts;
uniform float scale[5];
uniform uint frameOffset[5];
uniform uint nearHighOffset;

const float kInf = uintBitsToFloat(0x7F800000u);
const int kFloats = 25;
shared float red[kFloats][GROUP];
shared float sLut[768];  // the response, read from shared memory

uint byteOf(uint word, uint o) { return (word >> ((o & 3u) * 8u)) & 255u; }
uint nearByte(uint o) { return byteOf(nearWords[o >> 2], o); }

struct Reading {
  vec3 e;
  float peak, code, w;
  bool well;
};

float luma(vec3 c) { return 0.0722 * c.b + (0.7152 * c.g + 0.2126 * c.r); }

bool wellCoded(float code) { return code >= float(wellCode) && code < float(clipCode); }

Reading readFrame(int i, uint pixel) {
  const uint o = frameOffset[i] + 3u * pixel;
  // A pixel's three bytes lie in at most two words.
  const uint w0 = frameWords[o >> 2], w1 = frameWords[(o + 2u) >> 2];
  const uint b = byteOf(w0, o), g = byteOf((o & 3u) == 3u ? w1 : w0, o + 1u),
             r = byteOf(w1, o + 2u);
  const float s = scale[i];
  Reading x;
  x.e = vec3(sLut[r] * s, sLut[256u + g] * s, sLut[512u + b] * s);
  x.peak = max(x.e.r, max(x.e.g, x.e.b));
  x.code = float(max(b, max(g, r)));
  // The hat of Debevec and Malik over the radiance scale.
  const float hat = min(x.code - float(floorCode), float(clipCode) - x.code);
  x.w = x.code > float(floorCode) && x.code < float(clipCode) ? hat * (1.0 / s) : 0.0;
  x.well = wellCoded(x.code);
  return x;
}

// The newest frame's neighbourhood reading: green's response for the largest channel's code.
Reading readNear(uint code, float s) {
  Reading q;
  q.code = float(code);
  q.peak = sLut[256u + code] * s;
  q.well = wellCoded(q.code);
  return q;
}

// What a reading says of its pixel's radiance, as an interval (x: low, y: high).
vec2 boundsOf(Reading r, float s) {
  const bool dark = r.code <= float(floorCode), clipped = r.code >= float(clipCode);
  const float k = r.well ? 1.25 : 2.0, invK = r.well ? 0.8 : 0.5;
  const float lo = clipped ? belowClipLinear * s : r.peak * invK;
  const float hi = clipped ? kInf : r.peak * k;
  return vec2(dark ? 0.0 : lo, dark ? wellLinear * s : hi);
}

void main() {
  const uint lid = gl_LocalInvocationID.x;
  // A workgroup merges one of a row's `parts`, each a span of whole pixels.
  const int y = int(gl_WorkGroupID.x) / parts, part = int(gl_WorkGroupID.x) % parts;
  const int span = (width + parts - 1) / parts;
  const int x0 = part * span, x1 = min(width, x0 + span);
  for (uint i = lid; i < 768u; i += uint(GROUP)) sLut[i] = lut[i];
  barrier();
  float acc[kFloats];
  for (int k = 0; k < kFloats; ++k) acc[k] = 0.0;
  acc[5] = -1.0;
  acc[7] = 1.0;
  const int now = frames - 1;
  const float sNow = scale[now];
  for (int x = x0 + int(lid); x < x1; x += GROUP) {
    const uint p = uint(y) * uint(width) + uint(x);
    // The older frames in registers: every loop over them runs to the constant bound (indices
    // known at compile time), the newest apart.
    Reading r[4];
    for (int i = 0; i < 4; ++i)
      if (i < now) r[i] = readFrame(i, p);
    Reading n = readFrame(now, p);
    const vec2 bNow = boundsOf(n, sNow);
    float lost = -1.0;
    vec2 wide = bNow;
    bool edge = false;
    if (turned != 0) {
      const uint low = nearByte(p), high = nearByte(nearHighOffset + p);
      wide.x = min(wide.x, boundsOf(readNear(low, sNow), sNow).x);
      wide.y = max(wide.y, boundsOf(readNear(high, sNow), sNow).y);
      edge = float(high) >= float(clipCode);
    }
    // Where an older reading contradicts the newest, the newest wins.
    bool newestGivesWay = false;
    for (int i = 0; i < 4; ++i) {
      if (i >= now || JUDGE == 0) break;
      const bool both = r[i].well && n.well;
      const bool edgeOfSource = scale[i] > 1.02 * sNow && edge && both &&
                                r[i].peak > 1.5625 * n.peak;
      newestGivesWay = newestGivesWay || edgeOfSource;
      const vec2 b = boundsOf(r[i], scale[i]);
      const bool apart = b.x > wide.y || wide.x > b.y;
      const bool agree = turned != 0 ? !apart && both
                                     : both && r[i].peak < 1.5625 * n.peak &&
                                           1.5625 * r[i].peak > n.peak;
      const bool disagree =
          !edgeOfSource && (turned != 0 ? apart : (!agree && both) || (!both && apart));
      const float dq = 2.0 * (r[i].peak - n.peak) / (r[i].peak + n.peak);
      const float closeness = exp(-(dq * dq * inv2s2));
      r[i].w = disagree ? 0.0 : agree ? r[i].w * closeness : r[i].w;
      if (disagree) lost = max(lost, luma(r[i].e));
    }
    if (newestGivesWay) n.w = 0.0;
    // Two older readings where the shorter exposure reads brighter: the longer gives way.
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        if (JUDGE == 0 || i >= now || j >= now || j == i || !(scale[j] > 1.02 * scale[i]))
          continue;
        if (r[i].well && r[j].w > 0.0 && r[j].well && r[j].peak > 1.5625 * r[i].peak)
          r[i].w = 0.0;
      }
    // The weighted mean, oldest first; the clipped reading that bounds the pixel highest (the
    // first of equals); the longest exposure's.
    float sw = 0.0, kPeak = -1.0;
    vec3 c = vec3(0.0), kE = vec3(0.0), longE = n.e;
    bool wellSeen = false, hasClip = false;
    for (int i = 0; i < 5; ++i) {
      if (i > now) break;
      const Reading ri = i < now ? r[min(i, 3)] : n;
      sw += ri.w;
      wellSeen = wellSeen || (ri.w > 0.0 && ri.well);
      c += ri.w * ri.e;
      const bool higher = ri.code >= float(clipCode) && ri.peak > kPeak;
      hasClip = hasClip || higher;
      if (higher) kPeak = ri.peak, kE = ri.e;
      if (i == longest) longE = ri.e;
    }
    const bool measured = sw > 0.0, contradicted = lost >= 0.0;
    c = measured ? c * (1.0 / sw) : contradicted ? n.e : hasClip ? kE : longE;
    const bool clipped =
        !measured && ((contradicted && n.code >= float(clipCode)) || (!contradicted && hasClip));
    if (writeRgb != 0) rgb[3u * p] = c.r, rgb[3u * p + 1u] = c.g, rgb[3u * p + 2u] = c.b;
    // The row's sums, as the CPU's row kernel makes them.
    const float l = luma(c);
    const float seen = fresh != 0 ? previous[p] : 0.0;  // read before it is written
    luminance[p] = l;
    if (contradicted || seen > 1.25 * wide.y) acc[3] += max(max(lost, seen) - l, 0.0);
    acc[0] += l;
    if (clipped) acc[1] += l, acc[2] += max(l, reference[p]);
    if (!(clipped || wellSeen)) acc[4] += 1.0;
    if (l > acc[5]) {
      acc[5] = l, acc[6] = clipped ? 1.0 : 0.0, acc[7] = n.w > 0.0 ? 1.0 : 0.0;
      acc[8] = float(x);
    }
    if (project != 0) {
      for (int k = 0; k < 5; ++k) {
        const float wk = col[k * width + x];
        acc[9 + 3 * k] += wk * c.r, acc[10 + 3 * k] += wk * c.g, acc[11 + 3 * k] += wk * c.b;
      }
      acc[24] = max(acc[24], max(c.r, max(c.g, c.b)));
    }
  }
  for (int k = 0; k < kFloats; ++k) red[k][lid] = acc[k];
  barrier();
  for (uint stride = uint(GROUP) / 2u; stride > 0u; stride >>= 1) {
    if (lid < stride) {
      const uint o = lid + stride;
      for (int k = 0; k < 5; ++k) red[k][lid] += red[k][o];
      for (int k = 9; k < 24; ++k) red[k][lid] += red[k][o];
      red[24][lid] = max(red[24][lid], red[24][o]);
      // The brightest: the larger, or of equals the first pixel.
      if (red[5][o] > red[5][lid] || (red[5][o] == red[5][lid] && red[8][o] < red[8][lid]))
        for (int k = 5; k < 9; ++k) red[k][lid] = red[k][o];
    }
    barrier();
  }
  if (lid == 0u)
    for (int k = 0; k < kFloats; ++k) rows[int(gl_WorkGroupID.x) * kFloats + k] = red[k][0];
}
)";

// An older frame turned to the newest (align::turnCodes on the CPU): dst(d) = src(q d) for an
// equirect frame, each pixel bilinear over the four around where it reads from, in linear units,
// and coded back through the response's inverse table; a pixel whose corners are clipped by half
// their weight or more reads as the clipped corner of most weight. Each invocation writes four
// pixels, three whole words (a slot is a multiple of 12 bytes).
const char* const kTurnCs = R"(#version 430
layout(local_size_x = 64) in;
layout(std430, binding = 0) buffer Frames { uint frameWords[]; };
layout(std430, binding = 1) readonly buffer Lut { float lut[]; };
layout(std430, binding = 9) readonly buffer Recode { uint recodeWords[]; };
layout(std430, binding = 10) readonly buffer Nodes { float nodes[]; };
uniform int width, height, clipCode, nodesX, nodesY, polar;
uniform uint source, dest, first, last, span;
uniform mat3 q;
uniform vec3 inverseTop;
const float kPi = 3.14159265358979;

uint byteOf(uint word, uint o) { return (word >> ((o & 3u) * 8u)) & 255u; }
uint sourceByte(uint o) { return byteOf(frameWords[o >> 2], o); }
uint codeOf(int c, float v) {
  const uint i = clamp(floatBitsToUint(v * inverseTop[c]) >> 15, first, last) - first;
  const uint o = uint(c) * span + i;
  return byteOf(recodeWords[o >> 2], o);
}

// Where pixel (x, y) reads from: from the grid's nodes as the CPU interpolates them, or in the
// polar rows from q itself.
vec2 sourceOf(int x, int y) {
  if (y < polar || y >= height - polar) {
    const float theta = kPi * (float(y) + 0.5) / float(height);
    const float phi = 2.0 * kPi * (float(x) + 0.5) / float(width);
    const vec3 p = q * vec3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
    float azimuth = atan(p.y, p.x);
    if (azimuth < 0.0) azimuth += 2.0 * kPi;
    return vec2(azimuth / (2.0 * kPi) * float(width) - 0.5,
                acos(clamp(p.z, -1.0, 1.0)) / kPi * float(height) - 0.5);
  }
  const int j = min(y / 16, nodesY - 2);
  const int top = min(j * 16, height - 1), next = min((j + 1) * 16, height - 1);
  const float t = float(y - top) / float(max(1, next - top));
  const int i = x / 16;
  const int a = j * nodesX + i, b = a + nodesX;
  const float oa = nodes[a] + t * (nodes[b] - nodes[a]);
  const float ob = nodes[a + 1] + t * (nodes[b + 1] - nodes[a + 1]);
  const int rows = nodesX * nodesY;
  const float ra = nodes[rows + a] + t * (nodes[rows + b] - nodes[rows + a]);
  const float rb = nodes[rows + a + 1] + t * (nodes[rows + b + 1] - nodes[rows + a + 1]);
  const float s = float(x - 16 * i) * (1.0 / 16.0);
  return vec2(float(x) + oa + s * (ob - oa), ra + s * (rb - ra));
}

uvec3 turned(uint pixel) {
  const int x = int(pixel % uint(width)), y = int(pixel / uint(width));
  const vec2 from = sourceOf(x, y);
  const float fx = from.x, fy = clamp(from.y, 0.0, float(height - 1));
  int c0 = int(fx + float(width)) - width;
  const float ax = fx - float(c0);
  c0 += c0 < 0 ? width : 0;
  c0 -= c0 >= width ? width : 0;
  const int c1 = c0 + 1 == width ? 0 : c0 + 1;
  const int r0 = min(int(fy), height - 2);
  const float ay = fy - float(r0);
  const int at[4] = int[4](r0 * width + c0, r0 * width + c1, (r0 + 1) * width + c0,
                           (r0 + 1) * width + c1);
  const float weight[4] = float[4]((1.0 - ax) * (1.0 - ay), ax * (1.0 - ay), (1.0 - ax) * ay,
                                   ax * ay);
  float r = 0.0, g = 0.0, b = 0.0, unclipped = 0.0, most = -1.0;
  uvec3 result = uvec3(0u);
  for (int k = 0; k < 4; ++k) {
    const uint o = source + 3u * uint(at[k]);
    const uvec3 bgr = uvec3(sourceByte(o), sourceByte(o + 1u), sourceByte(o + 2u));
    if (max(bgr.x, max(bgr.y, bgr.z)) >= uint(clipCode)) {
      if (weight[k] > most) most = weight[k], result = bgr;
      continue;
    }
    unclipped += weight[k];
    b += weight[k] * lut[512u + bgr.x], g += weight[k] * lut[256u + bgr.y];
    r += weight[k] * lut[bgr.z];
  }
  if (unclipped <= 0.5) return result;  // the clipped corner of most weight
  const float inv = 1.0 / unclipped;
  return uvec3(codeOf(2, b * inv), codeOf(1, g * inv), codeOf(0, r * inv));
}

void main() {
  const uint i = gl_GlobalInvocationID.x, pixels = uint(width * height);
  if (4u * i >= pixels) return;
  uint bytes[12];
  for (uint j = 0u; j < 4u; ++j) {
    const uvec3 v = 4u * i + j < pixels ? turned(4u * i + j) : uvec3(0u);
    bytes[3u * j] = v.x, bytes[3u * j + 1u] = v.y, bytes[3u * j + 2u] = v.z;
  }
  for (uint w = 0u; w < 3u; ++w)
    frameWords[dest / 4u + 3u * i + w] = bytes[4u * w] | (bytes[4u * w + 1u] << 8) |
                                         (bytes[4u * w + 2u] << 16) | (bytes[4u * w + 3u] << 24);
}
)";

void setInt(GLuint program, const char* name, int value) {
  glUniform1i(glGetUniformLocation(program, name), value);
}
void setFloat(GLuint program, const char* name, float value) {
  glUniform1f(glGetUniformLocation(program, name), value);
}

}  // namespace

GpuMerge::GpuMerge(const GpuMergeShape& shape) : rowParts_(std::max(1, shape.rowParts)) {
  if (!hasCompute())
    throw ContextError("the bracket merge on the GPU needs compute shaders (GL 4.3)");
  const int group = shape.groupSize;
  if (group < 32 || group > 1024 || (group & (group - 1)) != 0)
    throw ContextError("the bracket merge on the GPU: a workgroup of " + std::to_string(group) +
                       " invocations (a power of two from 32 to 1024)");
  const std::string source = "#version 430\n#define GROUP " + std::to_string(group) +
                             "\n#define JUDGE " + (shape.judge ? "1" : "0") + "\n" + kMergeCs;
  program_ = linkCompute(source.c_str(), "the bracket merge");
  turn_ = linkCompute(kTurnCs, "the bracket's turn");
  const auto make = [](auto& buffers) {
    for (Buffer& b : buffers) {
      GLuint id = 0;
      glGenBuffers(1, &id);
      b = Buffer(id);
    }
  };
  make(buffers_), make(luminance_);
}

GpuMerge::~GpuMerge() = default;

void GpuMerge::fill(int binding, const void* data, std::size_t bytes) {
  const std::size_t b = std::size_t(binding);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffers_[b].get());
  const std::size_t size = std::max<std::size_t>((bytes + 3) / 4 * 4, 16);
  if (sizes_[b] < size) {
    while (glGetError() != GL_NO_ERROR) {
    }
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(size), nullptr, GL_DYNAMIC_DRAW);
    if (glGetError() == GL_OUT_OF_MEMORY)
      throw ContextError("the bracket merge on the GPU: out of GPU memory for " +
                         std::to_string(size >> 20) + " MB");
    sizes_[b] = size;
  }
  if (data) glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(bytes), data);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GLuint(binding), buffers_[b].get());
}

int GpuMerge::bindLuminance(const merge::FrameInput& in, std::size_t pixels) {
  if (pixels != luminancePixels_) {
    const std::size_t bytes = std::max<std::size_t>(pixels * sizeof(float), 16);
    for (Buffer& b : luminance_) {
      glBindBuffer(GL_SHADER_STORAGE_BUFFER, b.get());
      glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(bytes), nullptr, GL_DYNAMIC_DRAW);
    }
    luminancePixels_ = pixels;
    luminanceKeys_.forget();
  }
  // The last merges' luminance where a buffer still holds it; else uploaded into one no other
  // part of this merge uses; this merge's into the third.
  Keyed<3>& keys = luminanceKeys_;
  keys.startMerge();
  const int previous = keys.find(in.previousKey);
  int reference = in.referenceKey == in.previousKey ? previous : keys.find(in.referenceKey);
  const int out = keys.claim(0);
  const auto upload = [&](const float* data, std::uint64_t key) {
    const int k = keys.claim(key);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, luminance_[std::size_t(k)].get());
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(pixels * sizeof(float)), data);
    ++luminanceUploaded_;
    return k;
  };
  const int prev = previous >= 0 ? previous : upload(in.previous, in.previousKey);
  if (reference < 0)
    reference = in.referenceKey != 0 && in.referenceKey == in.previousKey
                    ? prev
                    : upload(in.reference, in.referenceKey);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kPrevious, luminance_[std::size_t(prev)].get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kReference, luminance_[std::size_t(reference)].get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kLuminance, luminance_[std::size_t(out)].get());
  keys.key[out] = in.luminanceKey;
  return out;
}

void GpuMerge::turnFrame(const merge::FrameInput& in, int frame, GLuint source, GLuint dest) {
  const merge::FrameInput::Recode& rc = in.recode;
  if (!rc.table[0])
    throw ContextError("the bracket merge on the GPU: a turn without the response's way back");
  const std::size_t span = (rc.last - rc.first + 1 + 3) / 4 * 4;
  std::vector<std::uint8_t> tables(3 * span, 0);
  for (int c = 0; c < 3; ++c)
    std::copy(rc.table[c], rc.table[c] + (rc.last - rc.first + 1),
              tables.begin() + std::ptrdiff_t(span * std::size_t(c)));
  if (tables != recode_) {  // uploaded once per response
    fill(kRecode, tables.data(), tables.size());
    recode_ = std::move(tables);
  }
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kRecode, buffers_[kRecode].get());
  const merge::FrameInput::Turn& turn = in.turn[frame];
  const std::size_t nodes = std::size_t(turn.nodesX) * std::size_t(turn.nodesY);
  if (!turn.offset || nodes < 4)
    throw ContextError("the bracket merge on the GPU: a turn without its grid of sources");
  std::vector<float> grid(turn.offset, turn.offset + nodes);
  grid.insert(grid.end(), turn.row, turn.row + nodes);
  fill(kNodes, grid.data(), grid.size() * sizeof(float));
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kFrames, buffers_[kFrames].get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kLut, buffers_[kLut].get());
  const GLuint p = turn_.get();
  glUseProgram(p);
  setInt(p, "width", in.width), setInt(p, "height", in.height), setInt(p, "clipCode", in.clip);
  setInt(p, "nodesX", turn.nodesX), setInt(p, "nodesY", turn.nodesY),
      setInt(p, "polar", turn.polar);
  glUniform1ui(glGetUniformLocation(p, "source"), source);
  glUniform1ui(glGetUniformLocation(p, "dest"), dest);
  glUniform1ui(glGetUniformLocation(p, "first"), rc.first);
  glUniform1ui(glGetUniformLocation(p, "last"), rc.last);
  glUniform1ui(glGetUniformLocation(p, "span"), GLuint(span));
  glUniformMatrix3fv(glGetUniformLocation(p, "q"), 1, GL_FALSE, in.turn[frame].q);
  glUniform3fv(glGetUniformLocation(p, "inverseTop"), 1, rc.inverseTop);
  const std::size_t quads = (std::size_t(in.width) * std::size_t(in.height) + 3) / 4;
  glDispatchCompute(GLuint((quads + 63) / 64), 1, 1);
  glUseProgram(0);
}

void GpuMerge::operator()(const merge::FrameInput& in, std::vector<merge::RowSums>& rows) {
  const std::size_t pixels = std::size_t(in.width) * std::size_t(in.height);
  // A slot: whole words, and whole groups of four pixels for the turn's writes.
  const std::size_t frameBytes = pixels * 3, stride = (frameBytes + 11) / 12 * 12;
  float lut[3 * 256];
  for (int c = 0; c < 3; ++c) std::copy(in.lut[c], in.lut[c] + 256, lut + 256 * c);
  fill(kLut, lut, sizeof lut);
  // The frames' codes, each in a slot, as they are; a frame still in a slot from an earlier merge
  // (its key) is not uploaded again.
  if (stride != slotStride_) {
    fill(kFrames, nullptr, stride * kSlots);
    slotStride_ = stride;
    slots_.forget();
  }
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffers_[kFrames].get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kFrames, buffers_[kFrames].get());
  int slotOf[merge::kMaxFrames];
  slots_.startMerge();
  for (int i = 0; i < in.frames; ++i) slotOf[i] = slots_.find(in.key[i]);
  for (int i = 0; i < in.frames; ++i)
    if (slotOf[i] < 0) {
      slotOf[i] = slots_.claim(in.key[i]);
      glBufferSubData(GL_SHADER_STORAGE_BUFFER, GLintptr(stride * std::size_t(slotOf[i])),
                      GLsizeiptr(frameBytes), in.bgr[i]);
      ++uploaded_;
    }
  // Older frames turned to the newest, each from its slot into one of its own.
  GLuint offsets[merge::kMaxFrames] = {};
  for (int i = 0; i < in.frames; ++i) {
    offsets[i] = GLuint(stride * std::size_t(slotOf[i]));
    if (!in.turn[i].apply) continue;
    const int into = slots_.claim(0);
    turnFrame(in, i, offsets[i], GLuint(stride * std::size_t(into)));
    offsets[i] = GLuint(stride * std::size_t(into));
  }
  if (std::any_of(std::begin(in.turn), std::end(in.turn), [](auto& t) { return t.apply; }))
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  const int out = bindLuminance(in, pixels);
  const bool turned = in.nearLow != nullptr;
  const std::size_t nearStride = (pixels + 3) / 4 * 4;
  fill(kNear, nullptr, turned ? 2 * nearStride : 4);
  if (turned) {
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(pixels), in.nearLow);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, GLintptr(nearStride), GLsizeiptr(pixels),
                    in.nearHigh);
  }
  kept_.reset();
  const std::size_t rgbBytes = pixels * 3 * sizeof(float);
  GLuint rgbBuffer = 0;  // where the merged frame is written
  if (in.rgbKept) {
    rgbBuffer = keptPool_.take(rgbBytes);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kRgb, rgbBuffer);
  } else {
    fill(kRgb, nullptr, in.rgb ? rgbBytes : 4);
    rgbBuffer = buffers_[kRgb].get();
  }
  const bool project = in.col[0] != nullptr;
  fill(kCol, nullptr, project ? 5 * std::size_t(in.width) * sizeof(float) : 4);
  if (project)
    for (int k = 0; k < 5; ++k)
      glBufferSubData(GL_SHADER_STORAGE_BUFFER, GLintptr(std::size_t(k) * in.width * sizeof(float)),
                      GLsizeiptr(std::size_t(in.width) * sizeof(float)), in.col[k]);
  const int parts = rowParts_;
  const std::size_t groups = std::size_t(in.height) * std::size_t(parts);
  fill(kRows, nullptr, groups * kRowFloats * sizeof(float));

  const GLuint p = program_.get();
  glUseProgram(p);
  setInt(p, "width", in.width), setInt(p, "frames", in.frames), setInt(p, "longest", in.longest);
  setInt(p, "floorCode", in.floor), setInt(p, "clipCode", in.clip);
  setInt(p, "wellCode", in.wellExposed);
  setFloat(p, "wellLinear", in.wellLinear), setFloat(p, "belowClipLinear", in.belowClipLinear);
  setFloat(p, "inv2s2", in.inv2s2);
  setInt(p, "fresh", in.fresh), setInt(p, "turned", turned),
      setInt(p, "writeRgb", in.rgb != nullptr || in.rgbKept);
  setInt(p, "project", project), setInt(p, "parts", parts);
  glUniform1fv(glGetUniformLocation(p, "scale"), merge::kMaxFrames, in.scale);
  glUniform1uiv(glGetUniformLocation(p, "frameOffset"), merge::kMaxFrames, offsets);
  glUniform1ui(glGetUniformLocation(p, "nearHighOffset"), GLuint(nearStride));
  glDispatchCompute(GLuint(groups), 1, 1);
  // (A kept frame is read by the drawing context's copy from a pixel buffer.)
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | (in.rgbKept ? GL_PIXEL_BUFFER_BARRIER_BIT : 0));
  glUseProgram(0);
  if (in.rgbKept) kept_ = keptPool_.give(in.width, in.height);

  std::vector<float> sums(groups * kRowFloats);
  const auto read = [](GLuint b, void* into, std::size_t bytes) {
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, b);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(bytes), into);
  };
  read(buffers_[kRows].get(), sums.data(), sums.size() * sizeof(float));
  if (in.luminanceBack)
    read(luminance_[std::size_t(out)].get(), in.luminance, pixels * sizeof(float));
  if (in.rgb) read(rgbBuffer, in.rgb, rgbBytes);
  // Each row's parts in order: their sums added, the brightest the larger (of equals the first).
  rows.assign(std::size_t(in.height), merge::RowSums{});
  for (std::size_t g = 0; g < groups; ++g) {
    const float* s = sums.data() + g * kRowFloats;
    merge::RowSums& r = rows[g / std::size_t(parts)];
    r.power += s[0], r.clippedPower += s[1], r.clippedEstimate += s[2], r.lostPower += s[3];
    r.dark += std::size_t(s[4]);
    if (s[5] > r.brightest)
      r.brightest = s[5], r.brightestClipped = s[6] > 0, r.brightestFresh = s[7] > 0;
    if (project) {
      for (int k = 0; k < 5; ++k)
        for (int c = 0; c < 3; ++c) r.col[k][c] += double(s[9 + 3 * k + c]);
      r.peak = std::max(r.peak, s[24]);
    }
  }
}

bool GpuMerge::readLuminance(std::uint64_t key, float* into) {
  const int k = luminanceKeys_.holding(key);
  if (k < 0) return false;
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, luminance_[std::size_t(k)].get());
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(luminancePixels_ * sizeof(float)),
                     into);
  return true;
}

}  // namespace lp::gl
