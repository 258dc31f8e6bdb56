// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/gl_program.h -- what every GPU feature's OpenGL half needs: compiling a compute
// program with the driver's log in the error, and sizes in MiB for memory errors
#pragma once
#include <cstdio>
#include <string>

#include "gl_api.h"
#include "penumbra/core/error.h"

namespace penumbra::render::gpu {

inline std::string mib(std::size_t bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f MiB", static_cast<double>(bytes) / (1024.0 * 1024.0));
  return buf;
}

/// Compiles and links one compute shader; throws Error(backend_unavailable) naming `what` with
/// the driver's log.
inline GLuint compile_compute_program(const GlApi& gl, const char* source, const std::string& what) {
  const GLuint shader = gl.CreateShader(GL_COMPUTE_SHADER);
  gl.ShaderSource(shader, 1, &source, nullptr);
  gl.CompileShader(shader);
  GLint ok = 0;
  gl.GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    gl.GetShaderInfoLog(shader, sizeof log, nullptr, log);
    gl.DeleteShader(shader);
    throw Error(ErrorCode::backend_unavailable, "GPU backend: the " + what + " shader does not compile: " + log);
  }
  const GLuint program = gl.CreateProgram();
  gl.AttachShader(program, shader);
  gl.LinkProgram(program);
  gl.DeleteShader(shader);
  gl.GetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    gl.GetProgramInfoLog(program, sizeof log, nullptr, log);
    gl.DeleteProgram(program);
    throw Error(ErrorCode::backend_unavailable, "GPU backend: the " + what + " shader does not link: " + log);
  }
  return program;
}

}  // namespace penumbra::render::gpu
