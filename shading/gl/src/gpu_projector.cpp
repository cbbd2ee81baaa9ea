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

// The first pass. A workgroup of 256 invocations covers 256 columns and `rowsPerGroup` rows;
// each invocation walks down its column, so neighbours read neighbouring texels. Equirect: the
// column's weights are constant, so an invocation sums value * row factor over its rows (six row
// factors x three channels) and multiplies by the five column integrals once at the end (as the
// CPU kernel sums columns first). Other layouts: nine weights per pixel from the CPU's table.
// Then a shared-memory tree sums the 27 values of the 256 invocations: 27 partials per group.
const char* const kReduceCs = R"(#version 430
layout(local_size_x = 256) in;
layout(binding = 0) uniform sampler2D frame;
layout(std430, binding = 0) readonly buffer Rows { float rowT[]; };      // 6 x height
layout(std430, binding = 1) readonly buffer Cols { float colT[]; };      // 5 x paddedWidth
layout(std430, binding = 2) readonly buffer Weights { float weights[]; };  // blocked, 9 per pixel
layout(std430, binding = 3) readonly buffer Decode { float decodeT[]; };   // 256
layout(std430, binding = 4) writeonly buffer Partial { float partial[]; }; // 27 x groups
uniform int width, height, paddedWidth, rowsPerGroup, equirect, codes;
const int rowOf[9] = int[9](0, 2, 1, 2, 4, 3, 5, 3, 4);
const int colOf[9] = int[9](0, 2, 0, 1, 4, 2, 0, 1, 3);
shared float red[27 * 256];

vec3 radiance(ivec2 p) {
  vec3 v = texelFetch(frame, p, 0).rgb;
  if (codes != 0) {
    uvec3 c = uvec3(round(v * 255.0));
    v = vec3(decodeT[c.r], decodeT[c.g], decodeT[c.b]);
  }
  return v;
}

void main() {
  const uint lid = gl_LocalInvocationID.x;
  const int j = int(gl_WorkGroupID.x) * 256 + int(lid);
  const int i0 = int(gl_WorkGroupID.y) * rowsPerGroup;
  const int i1 = min(i0 + rowsPerGroup, height);
  float acc[27];
  for (int q = 0; q < 27; ++q) acc[q] = 0.0;
  if (equirect != 0) {
    // The group's row factors into shared memory (red[] is free until the tree).
    for (int t = int(lid); t < 6 * (i1 - i0); t += 256)
      red[t] = rowT[(t / (i1 - i0)) * height + i0 + t % (i1 - i0)];
    barrier();
  }
  if (j < width) {
    if (equirect != 0) {
      const int n = i1 - i0;
      vec3 byRow[6];
      for (int r = 0; r < 6; ++r) byRow[r] = vec3(0.0);
      int i = 0;
      // Four rows a step: four fetches in flight before their sums need them.
      for (; i + 4 <= n; i += 4) {
        const vec3 v0 = radiance(ivec2(j, i0 + i)), v1 = radiance(ivec2(j, i0 + i + 1));
        const vec3 v2 = radiance(ivec2(j, i0 + i + 2)), v3 = radiance(ivec2(j, i0 + i + 3));
        for (int r = 0; r < 6; ++r)
          byRow[r] += red[r * n + i] * v0 + red[r * n + i + 1] * v1 + red[r * n + i + 2] * v2 +
                      red[r * n + i + 3] * v3;
      }
      for (; i < n; ++i) {
        const vec3 v = radiance(ivec2(j, i0 + i));
        for (int r = 0; r < 6; ++r) byRow[r] += red[r * n + i] * v;
      }
      float col[5];
      for (int c = 0; c < 5; ++c) col[c] = colT[c * paddedWidth + j];
      for (int k = 0; k < 9; ++k) {
        const vec3 s = byRow[rowOf[k]] * col[colOf[k]];
        acc[3 * k] = s.r, acc[3 * k + 1] = s.g, acc[3 * k + 2] = s.b;
      }
    } else {
      for (int i = i0; i < i1; ++i) {
        const int p = i * width + j;
        const int base = (p / 16) * 144 + p % 16;
        const vec3 v = radiance(ivec2(j, i));
        for (int k = 0; k < 9; ++k) {
          const float w = weights[base + 16 * k];
          acc[3 * k] += w * v.r, acc[3 * k + 1] += w * v.g, acc[3 * k + 2] += w * v.b;
        }
      }
    }
  }
  barrier();  // every row factor read before the tree overwrites them
  for (int q = 0; q < 27; ++q) red[q * 256 + lid] = acc[q];
  barrier();
  for (uint stride = 128u; stride > 0u; stride >>= 1) {
    if (lid < stride)
      for (int q = 0; q < 27; ++q) red[q * 256 + lid] += red[q * 256 + lid + stride];
    barrier();
  }
  if (lid < 27u) {
    const uint groups = gl_NumWorkGroups.x * gl_NumWorkGroups.y;
    const uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    partial[lid * groups + group] = red[lid * 256u];
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
    : spec_(spec), width_(width), height_(height) {
  if (!hasCompute()) throw ContextError("the GPU projection needs compute shaders (GL 4.3)");
  const Projector cpu(spec, width, height);  // the same tables as the CPU's projection
  reduce_ = linkCompute(kReduceCs, "the projection's reduction");
  finish_ = linkCompute(kFinishCs, "the projection's final sum");
  // 64 rows a group (the row factors fit in the shared array; liveprobe-gpu-bench's rows:N
  // measures other choices): each invocation keeps fetches in flight down its column.
  groupsX_ = (width + kGroupSize - 1) / kGroupSize;
  rowsPerGroup_ = std::min(rowsPerGroup > 0 ? std::min(rowsPerGroup, 1152) : 64, height);
  groupsY_ = (height + rowsPerGroup_ - 1) / rowsPerGroup_;
  if (const EquirectIntegrals* t = cpu.equirectIntegrals()) {
    std::vector<float> rows, cols;
    for (const auto& r : t->row) rows.insert(rows.end(), r.begin(), r.end());
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
  const GLuint p = reduce_.get();
  glUseProgram(p);
  glUniform1i(glGetUniformLocation(p, "frame"), 0);
  glUniform1i(glGetUniformLocation(p, "width"), width);
  glUniform1i(glGetUniformLocation(p, "height"), height);
  glUniform1i(glGetUniformLocation(p, "paddedWidth"),
              cpu.equirectIntegrals() ? GLint(cpu.equirectIntegrals()->col[0].size()) : 0);
  glUniform1i(glGetUniformLocation(p, "rowsPerGroup"), rowsPerGroup_);
  glUniform1i(glGetUniformLocation(p, "equirect"), cpu.equirectIntegrals() ? 1 : 0);
  glUseProgram(finish_.get());
  glUniform1i(glGetUniformLocation(finish_.get(), "groups"), groups());
  glUseProgram(0);
  checkGl("GpuProjector()");
}

GpuProjector::~GpuProjector() {
  for (auto& s : slots_)
    if (s.fence) glDeleteSync(s.fence);
}

void GpuProjector::dispatch(const FrameTexture& frame, const float* decode, bool bgr) {
  if (frame.width() != width_ || frame.height() != height_)
    throw Error("GPU projection: a " + std::to_string(frame.width()) + "x" +
                std::to_string(frame.height()) + " frame given to a projector for " +
                std::to_string(width_) + "x" + std::to_string(height_));
  const bool codes =
      frame.format() == PanoramaFormat::BgrU8 || frame.format() == PanoramaFormat::RgbU8;
  if (codes && !decode) throw Error("GPU projection: an 8-bit frame needs its decode table");
  if (pending_ == int(slots_.size())) read(true);  // both slots in flight: take the oldest
  if (codes && (!decodeSet_ || std::memcmp(lastDecode_.data(), decode, sizeof lastDecode_) != 0)) {
    std::memcpy(lastDecode_.data(), decode, sizeof lastDecode_);
    decodeSet_ = true;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, decode_.get());
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof lastDecode_, lastDecode_.data());
  }
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

}  // namespace lp::gl
