#include "liveprobe/gl/gpu_timer.h"

#include <stdexcept>

#include "liveprobe/gl/context.h"

namespace lp::gl {

GpuTimer::GpuTimer() {
  for (auto& f : queries_) glGenQueries(GLsizei(f.size()), f.data());
  GLint bits = 0;
  glGetQueryiv(GL_TIME_ELAPSED, GL_QUERY_COUNTER_BITS, &bits);
  // A software rasterizer's queries time its own threads' queue, not a GPU (llvmpipe answers 0
  // or a few nanoseconds): no GPU timer there.
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  hasTimer_ = bits > 0 && !isSoftwareRenderer(renderer ? renderer : "");
}

GpuTimer::~GpuTimer() {
  for (auto& f : queries_) glDeleteQueries(GLsizei(f.size()), f.data());
}

void GpuTimer::beginFrame() {
  frame_ = (frame_ + 1) % int(queries_.size());
  // The slot about to be reused was asked for kLatency frames ago: read what finished.
  justRead_ = {};
  auto& asked = asked_[std::size_t(frame_)];
  for (int s = 0; s < kStages; ++s) {
    if (!asked[std::size_t(s)]) continue;
    asked[std::size_t(s)] = false;
    const GLuint q = queries_[std::size_t(frame_)][std::size_t(s)];
    GLint available = 0;
    glGetQueryObjectiv(q, GL_QUERY_RESULT_AVAILABLE, &available);
    if (!available) continue;  // still running: skip it rather than wait
    GLuint64 ns = 0;
    glGetQueryObjectui64v(q, GL_QUERY_RESULT, &ns);
    ++answered_;
    if (ns > 0) ++nonZero_;
    latest_[std::size_t(s)] = justRead_[std::size_t(s)] = double(ns) * 1e-6;
  }
  if (answered_ >= 8 && nonZero_ == 0) hasTimer_ = false;
}

void GpuTimer::begin(Stage stage) {
  if (frame_ < 0) throw std::logic_error("GpuTimer::begin before beginFrame");
  if (open_) throw std::logic_error("GpuTimer: timer queries do not nest");
  open_ = true;
  asked_[std::size_t(frame_)][stage] = true;
  glBeginQuery(GL_TIME_ELAPSED, queries_[std::size_t(frame_)][stage]);
}

void GpuTimer::end() {
  if (!open_) throw std::logic_error("GpuTimer::end without begin");
  open_ = false;
  glEndQuery(GL_TIME_ELAPSED);
}

std::optional<double> GpuTimer::ms(Stage stage) const {
  if (!hasTimer_) return std::nullopt;
  return latest_[stage];
}

std::optional<double> GpuTimer::justRead(Stage stage) const {
  if (!hasTimer_) return std::nullopt;
  return justRead_[stage];
}

}  // namespace lp::gl
