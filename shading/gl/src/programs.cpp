// clang-format off: glad's header must come first, standing in for <GL/gl.h>.
#include "liveprobe/gl/gl.h"
// clang-format on

#include <initializer_list>
#include <string>

#include "liveprobe/gl/context.h"
#include "programs.h"

namespace lp::gl {

namespace {

Shader compile(GLenum type, const char* src, const char* name) {
  Shader s(glCreateShader(type));
  glShaderSource(s.get(), 1, &src, nullptr);
  glCompileShader(s.get());
  GLint ok = 0;
  glGetShaderiv(s.get(), GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetShaderInfoLog(s.get(), sizeof log, nullptr, log);
    throw ContextError(std::string("compiling ") + name + ": " + log);
  }
  return s;
}

Program link(std::initializer_list<const Shader*> shaders, const char* name) {
  Program p(glCreateProgram());
  for (const Shader* s : shaders) glAttachShader(p.get(), s->get());
  glLinkProgram(p.get());
  GLint ok = 0;
  glGetProgramiv(p.get(), GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetProgramInfoLog(p.get(), sizeof log, nullptr, log);
    throw ContextError(std::string("linking ") + name + ": " + log);
  }
  return p;
}

}  // namespace

Program linkProgram(const char* vs, const char* fs, const char* name) {
  const Shader v = compile(GL_VERTEX_SHADER, vs, name), f = compile(GL_FRAGMENT_SHADER, fs, name);
  return link({&v, &f}, name);
}

Program linkCompute(const char* cs, const char* name) {
  const Shader c = compile(GL_COMPUTE_SHADER, cs, name);
  return link({&c}, name);
}

}  // namespace lp::gl
