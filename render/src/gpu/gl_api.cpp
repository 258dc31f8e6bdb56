// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/gl_api.cpp -- resolving the OpenGL entry points
#include "gl_api.h"

#include <cstdio>

#include "penumbra/core/error.h"

namespace penumbra::render::gpu {

GlApi load_gl(const EglApi& egl) {
  GlApi gl;
#define PNB_GL_LOAD(type, name)                                                                          \
  gl.name = reinterpret_cast<type>(egl.GetProcAddress("gl" #name));                                     \
  if (gl.name == nullptr)                                                                                \
    throw Error(ErrorCode::backend_unavailable,                                                          \
                "GPU backend: the OpenGL driver behind '" + egl.library_path + "' lacks gl" #name " (OpenGL 4.5 needed)");
  PNB_GL_FUNCTIONS(PNB_GL_LOAD)
#undef PNB_GL_LOAD
  return gl;
}

std::string gl_error_text(GLenum code) {
  const char* name = "unknown GL error";
  switch (code) {
    case GL_NO_ERROR: name = "GL_NO_ERROR"; break;
    case GL_INVALID_ENUM: name = "GL_INVALID_ENUM"; break;
    case GL_INVALID_VALUE: name = "GL_INVALID_VALUE"; break;
    case GL_INVALID_OPERATION: name = "GL_INVALID_OPERATION"; break;
    case GL_OUT_OF_MEMORY: name = "GL_OUT_OF_MEMORY"; break;
    default: break;
  }
  char hex[16];
  std::snprintf(hex, sizeof hex, "0x%04x", static_cast<unsigned>(code));
  return std::string(name) + " (" + hex + ")";
}

}  // namespace penumbra::render::gpu
