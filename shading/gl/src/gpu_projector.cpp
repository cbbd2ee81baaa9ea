// clang-format off: glad's header must come first, standing in for <GL/gl.h>.
#include "liveprobe/gl/gl.h"
// clang-format on

#include <algorithm>
#include <cstring>
#include <string>

#include "liveprobe/gl/context.h"
#include "liveprobe/gl/gpu_projector.h"
#include "liveprobe/gl/renderer.h"
#include "liveprobe/sh/error.h"
#include "programs.h"

namespace lp::gl {

namespace {

constexpr int kGroupSize = 256;
/// The most rows a group of the first pass sums: their row factors (8 floats each) share the
/// shared array that later holds 9 x 256 of the group's sums.
constexpr int kMaxRowsPerGroup = 9 * kGroupSize / 8;

// The first pass, compiled with EQUIRECT 1 for the equirect layout, 0 for the others. A
// workgroup of 256 invocations covers 256 columns and `rowsPerGroup` rows; each invocation walks
// down its column, so neighbours read neighbouring texels.
//   Equirect: the column's weights are constant, so an invocation sums value * row factor over
//   its rows (six row factors x three channels, in registers) and multiplies by the five column
//   integrals once at the end, as the CPU kernel sums columns first. The group's row factors sit
//   in shared memory (8 floats a row, read by every invocation at once).
//   Other layouts: nine weights per pixel from the CPU's table.
// 8-bit frames are decoded through the 256-entry table, copied into shared memory per group.
// Then the group's 27 x 256 sums go through shared memory nine values at a time (little shared
// memory, so many groups share a multiprocessor and keep its fetches in flight): 216
// invocations sum 32 each, 27 sum the last 8, 27 partials per group.
const char* const kReduceCs = R"(
layout(local_size_x = 256) in;
layout(binding = 0) uniform sampler2D frame;
layout(std430, binding = 0) readonly buffer Rows { float rowT[]; };      // 8 x height
layout(std430, binding = 1) readonly buffer Cols { float colT[]; };      // 5 x paddedWidth
layout(std430, binding = 2) readonly buffer Weights { float weights[]; };  // blocked, 9 per pixel
layout(std430, binding = 3) readonly buffer Decode { float decodeT[]; };   // 256
layout(std430, binding = 4) writeonly buffer Partial { float partial[]; }; // 27 x groups
uniform int width, height, paddedWidth, rowsPerGroup, codes;
shared float red[9 * 256];
shared float decodeS[256];

vec3 radiance(int j, int i) {
  vec3 v = texelFetch(frame, ivec2(j, i), 0).rgb;
  if (codes != 0) {
    const uvec3 c = uvec3(v * 255.0 + 0.5);
    v = vec3(decodeS[c.r], decodeS[c.g], decodeS[c.b]);
  }
  return v;
}

void main() {
  const int lid = int(gl_LocalInvocationID.x);
  const int j = int(gl_WorkGroupID.x) * 256 + lid;
  const int i0 = int(gl_WorkGroupID.y) * rowsPerGroup;
  const int n = min(rowsPerGroup, height - i0);
  if (codes != 0) decodeS[lid] = decodeT[lid];
#if EQUIRECT
  for (int t = lid; t < 8 * n; t += 256) red[t] = rowT[8 * i0 + t];
  barrier();
  vec3 b0 = vec3(0.0), b1 = vec3(0.0), b2 = vec3(0.0), b3 = vec3(0.0), b4 = vec3(0.0),
       b5 = vec3(0.0);
#define ROW(v, r)                                                                  \
  b0 += red[8 * (r)] * v, b1 += red[8 * (r) + 1] * v, b2 += red[8 * (r) + 2] * v, \
  b3 += red[8 * (r) + 3] * v, b4 += red[8 * (r) + 4] * v, b5 += red[8 * (r) + 5] * v
  if (j < width) {
    int i = 0;
    // Eight rows a step: eight fetches in flight before their sums need them.
    for (; i + 8 <= n; i += 8) {
      const vec3 v0 = radiance(j, i0 + i), v1 = radiance(j, i0 + i + 1);
      const vec3 v2 = radiance(j, i0 + i + 2), v3 = radiance(j, i0 + i + 3);
      const vec3 v4 = radiance(j, i0 + i + 4), v5 = radiance(j, i0 + i + 5);
      const vec3 v6 = radiance(j, i0 + i + 6), v7 = radiance(j, i0 + i + 7);
      ROW(v0, i); ROW(v1, i + 1); ROW(v2, i + 2); ROW(v3, i + 3);
      ROW(v4, i + 4); ROW(v5, i + 5); ROW(v6, i + 6); ROW(v7, i + 7);
    }
    for (; i < n; ++i) {
      const vec3 v = radiance(j, i0 + i);
      ROW(v, i);
    }
  }
  float c0 = 0.0, c1 = 0.0, c2 = 0.0, c3 = 0.0, c4 = 0.0;
  if (j < width)
    c0 = colT[j], c1 = colT[paddedWidth + j], c2 = colT[2 * paddedWidth + j],
    c3 = colT[3 * paddedWidth + j], c4 = colT[4 * paddedWidth + j];
  // Y_k's row and column factors, as lp::Projector pairs them (rows 0..5, columns 0..4).
  const vec3 s[9] = vec3[9](b0 * c0, b2 * c2, b1 * c0, b2 * c1, b4 * c4, b3 * c2, b5 * c0,
                            b3 * c1, b4 * c3);
  float acc[27];
  for (int k = 0; k < 9; ++k) acc[3 * k] = s[k].r, acc[3 * k + 1] = s[k].g, acc[3 * k + 2] = s[k].b;
#else
  barrier();  // the decode table in place
  float acc[27];
  for (int q = 0; q < 27; ++q) acc[q] = 0.0;
  if (j < width)
    for (int i = i0; i < i0 + n; ++i) {
      const int p = i * width + j;
      const int base = (p / 16) * 144 + p % 16;
      const vec3 v = radiance(j, i);
      for (int k = 0; k < 9; ++k) {
        const float w = weights[base + 16 * k];
        acc[3 * k] += w * v.r, acc[3 * k + 1] += w * v.g, acc[3 * k + 2] += w * v.b;
      }
    }
#endif
  // Nine values at a time: invocation lid (< 216) sums value q = lid / 8 of invocations
  // lid % 8, lid % 8 + 8, ... (32 of them), in the round that holds q.
  float sum = 0.0;
  for (int round = 0; round < 3; ++round) {
    barrier();  // the row factors, or the last round's values, read
    for (int q = 0; q < 9; ++q) red[9 * lid + q] = acc[9 * round + q];
    barrier();
    if (lid >= 72 * round && lid < 72 * round + 72) {
      const int q = (lid >> 3) - 9 * round, part = lid & 7;
      for (int l = part; l < 256; l += 8) sum += red[9 * l + q];
    }
  }
  barrier();
  if (lid < 216) red[lid] = sum;
  barrier();
  if (lid < 27) {
    float total = 0.0;
    for (int part = 0; part < 8; ++part) total += red[8 * lid + part];
    const int groups = int(gl_NumWorkGroups.x * gl_NumWorkGroups.y);
    const int group = int(gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x);
    partial[lid * groups + group] = total;
  }
}
)";

// The second pass: workgroup q sums value q of every group's partials (stored value-major, so
// neighbouring invocations read neighbouring floats).
const char* const kFinishCs = R"(#version 430
layout(local_size_x = 256) in;
layout(std430, binding = 4) readonly buffer Partial { float partial[]; };
layout(std430, binding = 5) writeonly buffer Result { float result[]; };
uniform int groups;
shared float red[256];
void main() {
  const uint lid = gl_LocalInvocationID.x;
  const int q = int(gl_WorkGroupID.x);
  float acc = 0.0;
  for (int g = int(lid); g < groups; g += 256) acc += partial[q * groups + g];
  red[lid] = acc;
  barrier();
  for (uint stride = 128u; stride > 0u; stride >>= 1) {
    if (lid < stride) red[lid] += red[lid + stride];
    barrier();
  }
  if (lid == 0u) result[q] = red[0];
}
)";

// Each row's largest channel value: workgroup i reads row i (256 invocations across it), decodes
// 8-bit codes, and halves a shared array down to the maximum.
const char* const kPeaksCs = R"(#version 430
layout(local_size_x = 256) in;
layout(binding = 0) uniform sampler2D frame;
layout(std430, binding = 3) readonly buffer Decode { float decodeT[]; };
layout(std430, binding = 6) writeonly buffer Peaks { float peaks[]; };
uniform int width, codes;
shared float red[256];
void main() {
  const uint lid = gl_LocalInvocationID.x;
  const int i = int(gl_WorkGroupID.x);
  float m = 0.0;
  for (int j = int(lid); j < width; j += 256) {
    vec3 v = texelFetch(frame, ivec2(j, i), 0).rgb;
    if (codes != 0) {
      const uvec3 c = uvec3(v * 255.0 + 0.5);
      v = vec3(decodeT[c.r], decodeT[c.g], decodeT[c.b]);
    }
    m = max(m, max(v.r, max(v.g, v.b)));
  }
  red[lid] = m;
  barrier();
  for (uint stride = 128u; stride > 0u; stride >>= 1) {
    if (lid < stride) red[lid] = max(red[lid], red[lid + stride]);
    barrier();
  }
  if (lid == 0u) peaks[i] = red[0];
}
)";

struct TexFormat {
  GLenum internal, format, type;
};

TexFormat texFormat(PanoramaFormat f) {
  switch (f) {
    case PanoramaFormat::RgbF32:
      return {GL_RGB32F, GL_RGB, GL_FLOAT};
    case PanoramaFormat::RgbF16:
      return {GL_RGB16F, GL_RGB, GL_HALF_FLOAT};
    case PanoramaFormat::BgrU8:
    case PanoramaFormat::RgbU8:
      return {GL_RGB8, GL_RGB, GL_UNSIGNED_BYTE};
  }
  return {GL_RGB32F, GL_RGB, GL_FLOAT};
}

std::size_t bytesPerPixel(PanoramaFormat f) {
  PanoramaView v;
  v.format = f;
  return v.bytesPerPixel();
}

Buffer storageBuffer(const void* data, std::size_t bytes) {
  GLuint id = 0;
  glGenBuffers(1, &id);
  Buffer b(id);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, id);
  glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(std::max<std::size_t>(bytes, 16)), data,
               data ? GL_STATIC_DRAW : GL_DYNAMIC_COPY);
  return b;
}

/// Rows a first-pass group sums where the caller does not say: enough groups to fill a large GPU
/// (about 768), each invocation summing 16 to 256 rows, a multiple of 4 (liveprobe-gpu-bench's
/// rows:N runs measure the choice).
int defaultRowsPerGroup(int width, int height) {
  const int groupsX = (width + kGroupSize - 1) / kGroupSize;
  const int rows = (height * groupsX + 767) / 768;
  return std::clamp((rows + 3) / 4 * 4, 16, 256);
}

/// Waits for a fence (if any) and deletes it.
void waitAndDelete(GLsync& fence) {
  if (!fence) return;
  while (glClientWaitSync(fence, GL_SYNC_FLUSH_COMMANDS_BIT, 1'000'000'000) == GL_TIMEOUT_EXPIRED) {
  }
  glDeleteSync(fence);
  fence = nullptr;
}

}  // namespace

bool hasCompute() {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  return (major > 4 || (major == 4 && minor >= 3)) && glDispatchCompute != nullptr;
}

// ---- FrameTexture ---------------------------------------------------------------------------

std::size_t FrameTexture::frameBytes() const {
  return std::size_t(width_) * std::size_t(height_) * bytesPerPixel(format_);
}

void FrameTexture::allocate(PanoramaFormat format, int width, int height) {
  for (auto& f : fence_) waitAndDelete(f);
  for (int b = 0; b < 2; ++b)
    if (mapped_[b] && !persistent_) {
      glBindBuffer(GL_PIXEL_UNPACK_BUFFER, pbo_[b].get());
      glUnmapBuffer(GL_PIXEL_UNPACK_BUFFER);
    }
  format_ = format, width_ = width, height_ = height;
  const TexFormat tf = texFormat(format);
  GLuint id = 0;
  glGenTextures(1, &id);
  texture_.reset(id);
  glBindTexture(GL_TEXTURE_2D, id);
  glTexStorage2D(GL_TEXTURE_2D, 1, tf.internal, width, height);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  persistent_ = (major > 4 || (major == 4 && minor >= 4)) && glBufferStorage != nullptr;
  const auto bytes = GLsizeiptr(frameBytes());
  for (int b = 0; b < 2; ++b) {
    glGenBuffers(1, &id);
    pbo_[b].reset(id);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, id);
    mapped_[b] = nullptr;
    if (persistent_) {
      const GLbitfield flags = GL_MAP_WRITE_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
      glBufferStorage(GL_PIXEL_UNPACK_BUFFER, bytes, nullptr, flags);
      mapped_[b] = glMapBufferRange(GL_PIXEL_UNPACK_BUFFER, 0, bytes, flags);
      if (!mapped_[b]) throw ContextError("cannot map a pixel-buffer object persistently");
    } else {
      glBufferData(GL_PIXEL_UNPACK_BUFFER, bytes, nullptr, GL_STREAM_DRAW);
    }
  }
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  next_ = 0;
}

void* FrameTexture::map(PanoramaFormat format, int width, int height) {
  if (width <= 0 || height <= 0) throw Error("frame upload: empty frame");
  if (!texture_.isValid() || format != format_ || width != width_ || height != height_)
    allocate(format, width, height);
  waitAndDelete(fence_[next_]);  // the transfer from this buffer two frames ago
  writing_ = true;
  if (persistent_) return mapped_[next_];
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, pbo_[next_].get());
  void* p = glMapBufferRange(GL_PIXEL_UNPACK_BUFFER, 0, GLsizeiptr(frameBytes()),
                             GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  if (!p) throw ContextError("cannot map a pixel-buffer object");
  mapped_[next_] = p;
  return p;
}

void FrameTexture::commit() {
  if (!writing_) throw Error("frame upload: commit() without map()");
  writing_ = false;
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, pbo_[next_].get());
  if (!persistent_) {
    glUnmapBuffer(GL_PIXEL_UNPACK_BUFFER);
    mapped_[next_] = nullptr;
  }
  const TexFormat tf = texFormat(format_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glBindTexture(GL_TEXTURE_2D, texture_.get());
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width_, height_, tf.format, tf.type, nullptr);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  fence_[next_] = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  next_ ^= 1;
}

void FrameTexture::upload(const PanoramaView& frame) {
  auto* dst = static_cast<std::uint8_t*>(map(frame.format, frame.width, frame.height));
  const std::size_t row = frame.bytesPerPixel() * std::size_t(frame.width);
  const auto* src = static_cast<const std::uint8_t*>(frame.data);
  if (frame.strideBytes() == row) {
    std::memcpy(dst, src, row * std::size_t(frame.height));
  } else {
    for (int i = 0; i < frame.height; ++i)
      std::memcpy(dst + row * std::size_t(i), src + frame.strideBytes() * std::size_t(i), row);
  }
  commit();
}

// ---- GpuProjector ---------------------------------------------------------------------------

GpuProjector::GpuProjector(const LayoutSpec& spec, int width, int height, int rowsPerGroup)
    : GpuProjector(Projector(spec, width, height), rowsPerGroup) {}

GpuProjector::GpuProjector(const Projector& cpu, int rowsPerGroup)
    : spec_(cpu.spec()), width_(cpu.width()), height_(cpu.height()) {
  if (!hasCompute()) throw ContextError("the GPU projection needs compute shaders (GL 4.3)");
  const int width = width_, height = height_;
  const EquirectIntegrals* t = cpu.equirectIntegrals();
  const std::string reduce =
      std::string("#version 430\n#define EQUIRECT ") + (t ? "1" : "0") + "\n" + kReduceCs;
  reduce_ = linkCompute(reduce.c_str(), "the projection's reduction");
  finish_ = linkCompute(kFinishCs, "the projection's final sum");
  peaks_ = linkCompute(kPeaksCs, "the row peaks");
  groupsX_ = (width + kGroupSize - 1) / kGroupSize;
  rowsPerGroup_ = std::min(rowsPerGroup > 0 ? std::min(rowsPerGroup, kMaxRowsPerGroup)
                                            : defaultRowsPerGroup(width, height),
                           height);
  groupsY_ = (height + rowsPerGroup_ - 1) / rowsPerGroup_;
  if (t) {
    std::vector<float> rows(std::size_t(height) * 8, 0.0f), cols;
    for (std::size_t r = 0; r < t->row.size(); ++r)
      for (std::size_t i = 0; i < std::size_t(height); ++i) rows[8 * i + r] = t->row[r][i];
    for (const auto& c : t->col) cols.insert(cols.end(), c.begin(), c.end());
    rows_ = storageBuffer(rows.data(), rows.size() * sizeof(float));
    cols_ = storageBuffer(cols.data(), cols.size() * sizeof(float));
    weights_ = storageBuffer(nullptr, 16);
  } else {
    const auto& w = cpu.blockedWeights();
    rows_ = storageBuffer(nullptr, 16);
    cols_ = storageBuffer(nullptr, 16);
    weights_ = storageBuffer(w.data(), w.size() * sizeof(float));
  }
  decode_ = storageBuffer(nullptr, 256 * sizeof(float));
  partial_ = storageBuffer(nullptr, std::size_t(groups()) * 27 * sizeof(float));
  for (auto& s : slots_) s.result = storageBuffer(nullptr, 27 * sizeof(float));
  rowPeaks_ = storageBuffer(nullptr, std::size_t(height) * sizeof(float));
  const GLuint p = reduce_.get();
  glUseProgram(p);
  glUniform1i(glGetUniformLocation(p, "frame"), 0);
  glUniform1i(glGetUniformLocation(p, "width"), width);
  glUniform1i(glGetUniformLocation(p, "height"), height);
  glUniform1i(glGetUniformLocation(p, "paddedWidth"),
              cpu.equirectIntegrals() ? GLint(cpu.equirectIntegrals()->col[0].size()) : 0);
  glUniform1i(glGetUniformLocation(p, "rowsPerGroup"), rowsPerGroup_);
  glUseProgram(finish_.get());
  glUniform1i(glGetUniformLocation(finish_.get(), "groups"), groups());
  glUseProgram(peaks_.get());
  glUniform1i(glGetUniformLocation(peaks_.get(), "frame"), 0);
  glUniform1i(glGetUniformLocation(peaks_.get(), "width"), width);
  glUseProgram(0);
  checkGl("GpuProjector()");
}

GpuProjector::~GpuProjector() {
  for (auto& s : slots_)
    if (s.fence) glDeleteSync(s.fence);
}

namespace {
bool isCodes(const FrameTexture& frame) {
  return frame.format() == PanoramaFormat::BgrU8 || frame.format() == PanoramaFormat::RgbU8;
}
}  // namespace

void GpuProjector::setDecode(const FrameTexture& frame, const float* decode) {
  if (frame.width() != width_ || frame.height() != height_)
    throw Error("GPU projection: a " + std::to_string(frame.width()) + "x" +
                std::to_string(frame.height()) + " frame given to a projector for " +
                std::to_string(width_) + "x" + std::to_string(height_));
  const bool codes = isCodes(frame);
  if (codes && !decode) throw Error("GPU projection: an 8-bit frame needs its decode table");
  if (codes && (!decodeSet_ || std::memcmp(lastDecode_.data(), decode, sizeof lastDecode_) != 0)) {
    std::memcpy(lastDecode_.data(), decode, sizeof lastDecode_);
    decodeSet_ = true;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, decode_.get());
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof lastDecode_, lastDecode_.data());
  }
}

void GpuProjector::dispatch(const FrameTexture& frame, const float* decode, bool bgr) {
  if (pending_ == int(slots_.size())) read(true);  // both slots in flight: take the oldest
  setDecode(frame, decode);
  const bool codes = isCodes(frame);
  Slot& slot = slots_[std::size_t((head_ + pending_) % int(slots_.size()))];
  slot.bgr = bgr;
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, frame.texture());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, rows_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, cols_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, weights_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, decode_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, partial_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, slot.result.get());
  glUseProgram(reduce_.get());
  glUniform1i(glGetUniformLocation(reduce_.get(), "codes"), codes ? 1 : 0);
  glDispatchCompute(GLuint(groupsX_), GLuint(groupsY_), 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  glUseProgram(finish_.get());
  glDispatchCompute(27, 1, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  glUseProgram(0);
  slot.fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  glFlush();
  ++pending_;
}

std::optional<Sh9> GpuProjector::read(bool wait) {
  if (pending_ == 0) return std::nullopt;
  Slot& slot = slots_[std::size_t(head_)];
  if (!wait) {
    const GLenum s = glClientWaitSync(slot.fence, 0, 0);
    if (s == GL_TIMEOUT_EXPIRED) return std::nullopt;
  }
  waitAndDelete(slot.fence);
  std::array<float, 27> sums{};
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, slot.result.get());
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof sums, sums.data());
  head_ = (head_ + 1) % int(slots_.size());
  --pending_;
  Sh9 out;
  for (int k = 0; k < kShCount; ++k)
    out.c[k] = slot.bgr ? Rgb(sums[3 * k + 2], sums[3 * k + 1], sums[3 * k])
                        : Rgb(sums[3 * k], sums[3 * k + 1], sums[3 * k + 2]);
  return out;
}

Sh9 GpuProjector::project(const FrameTexture& frame, const float* decode, bool bgr) {
  while (pending_ > 0) read(true);
  dispatch(frame, decode, bgr);
  return *read(true);
}

std::vector<float> GpuProjector::rowPeaks(const FrameTexture& frame, const float* decode) {
  setDecode(frame, decode);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, frame.texture());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, decode_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, rowPeaks_.get());
  glUseProgram(peaks_.get());
  glUniform1i(glGetUniformLocation(peaks_.get(), "codes"), isCodes(frame) ? 1 : 0);
  glDispatchCompute(GLuint(height_), 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glUseProgram(0);
  std::vector<float> peaks(static_cast<std::size_t>(height_));
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, rowPeaks_.get());
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(peaks.size() * sizeof(float)),
                     peaks.data());
  return peaks;
}

// ---- GpuFrameProjection ---------------------------------------------------------------------

Sh9 GpuFrameProjection::operator()(const ProjectionJob& job) {
  const PanoramaView& v = job.view;
  if (!projector_ || job.tablesId != tablesId_) {
    projector_ = std::make_unique<GpuProjector>(job.tables);
    tablesId_ = job.tablesId;
  }
  frame_.upload(v);
  const Sh9 whole = projector_->project(frame_, v.decode, v.format == PanoramaFormat::BgrU8);
  if (job.rowPeaks) *job.rowPeaks = projector_->rowPeaks(frame_, v.decode);
  return whole;
}

}  // namespace lp::gl
