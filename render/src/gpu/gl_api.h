// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/gl_api.h -- the OpenGL 4.5 entry points the GPU backend uses, via eglGetProcAddress
#pragma once
#include <GL/glcorearb.h>

#include <string>

#include "egl_loader.h"

namespace penumbra::render::gpu {

#define PNB_GL_FUNCTIONS(X)                                       \
  X(PFNGLGETSTRINGPROC, GetString)                                \
  X(PFNGLGETSTRINGIPROC, GetStringi)                              \
  X(PFNGLGETINTEGERVPROC, GetIntegerv)                            \
  X(PFNGLGETINTEGER64VPROC, GetInteger64v)                        \
  X(PFNGLGETINTEGERI_VPROC, GetIntegeri_v)                        \
  X(PFNGLGETERRORPROC, GetError)                                  \
  X(PFNGLFINISHPROC, Finish)                                      \
  X(PFNGLCREATEBUFFERSPROC, CreateBuffers)                        \
  X(PFNGLNAMEDBUFFERDATAPROC, NamedBufferData)                    \
  X(PFNGLNAMEDBUFFERSUBDATAPROC, NamedBufferSubData)              \
  X(PFNGLGETNAMEDBUFFERSUBDATAPROC, GetNamedBufferSubData)        \
  X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                        \
  X(PFNGLBINDBUFFERBASEPROC, BindBufferBase)                      \
  X(PFNGLCREATESHADERPROC, CreateShader)                          \
  X(PFNGLSHADERSOURCEPROC, ShaderSource)                          \
  X(PFNGLCOMPILESHADERPROC, CompileShader)                        \
  X(PFNGLGETSHADERIVPROC, GetShaderiv)                            \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)                  \
  X(PFNGLDELETESHADERPROC, DeleteShader)                          \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram)                        \
  X(PFNGLATTACHSHADERPROC, AttachShader)                          \
  X(PFNGLLINKPROGRAMPROC, LinkProgram)                            \
  X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                          \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)                \
  X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                        \
  X(PFNGLUSEPROGRAMPROC, UseProgram)                              \
  X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)              \
  X(PFNGLPROGRAMUNIFORM1IPROC, ProgramUniform1i)                  \
  X(PFNGLPROGRAMUNIFORM2IPROC, ProgramUniform2i)                  \
  X(PFNGLPROGRAMUNIFORM1FPROC, ProgramUniform1f)                  \
  X(PFNGLPROGRAMUNIFORM2FPROC, ProgramUniform2f)                  \
  X(PFNGLPROGRAMUNIFORM3FPROC, ProgramUniform3f)                  \
  X(PFNGLPROGRAMUNIFORM4FPROC, ProgramUniform4f)                  \
  X(PFNGLPROGRAMUNIFORM1FVPROC, ProgramUniform1fv)                \
  X(PFNGLDISPATCHCOMPUTEPROC, DispatchCompute)                    \
  X(PFNGLMEMORYBARRIERPROC, MemoryBarrier)                        \
  X(PFNGLPROGRAMUNIFORM3IPROC, ProgramUniform3i)

struct GlApi {
#define PNB_GL_MEMBER(type, name) type name = nullptr;
  PNB_GL_FUNCTIONS(PNB_GL_MEMBER)
#undef PNB_GL_MEMBER
};

/// Resolves every entry point with eglGetProcAddress (EGL 1.5 / EGL_KHR_get_all_proc_addresses
/// resolve core functions too). Throws Error(backend_unavailable) naming the first one missing.
GlApi load_gl(const EglApi& egl);

/// "GL_OUT_OF_MEMORY (0x0505)".
std::string gl_error_text(GLenum code);

}  // namespace penumbra::render::gpu
