// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/egl_loader.h -- EGL entry points resolved at run time
//
// libEGL is opened with dlopen rather than linked, so that a program built with the GPU
// backend still starts on a node without EGL, and asking for the GPU there is a clear
// Error(backend_unavailable) instead of a loader failure.
#pragma once
#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <string>
#include <vector>

#include "penumbra/render/egl_device.h"

namespace penumbra::render::gpu {

/// The EGL 1.4 core entry points Penumbra calls: X(type, name) for eglName, resolved with dlsym.
#define PNB_EGL_FUNCTIONS(X)                                   \
  X(PFNEGLGETPROCADDRESSPROC, GetProcAddress)                  \
  X(PFNEGLGETERRORPROC, GetError)                              \
  X(PFNEGLQUERYSTRINGPROC, QueryString)                        \
  X(PFNEGLINITIALIZEPROC, Initialize)                          \
  X(PFNEGLTERMINATEPROC, Terminate)                            \
  X(PFNEGLBINDAPIPROC, BindAPI)                                \
  X(PFNEGLCHOOSECONFIGPROC, ChooseConfig)                      \
  X(PFNEGLCREATECONTEXTPROC, CreateContext)                    \
  X(PFNEGLDESTROYCONTEXTPROC, DestroyContext)                  \
  X(PFNEGLMAKECURRENTPROC, MakeCurrent)                        \
  X(PFNEGLGETCURRENTCONTEXTPROC, GetCurrentContext)            \
  X(PFNEGLGETCURRENTDISPLAYPROC, GetCurrentDisplay)            \
  X(PFNEGLGETCURRENTSURFACEPROC, GetCurrentSurface)

struct EglApi {
  std::string library_path;
  std::string client_extensions;  ///< eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS)
#define PNB_EGL_MEMBER(type, name) type name = nullptr;
  PNB_EGL_FUNCTIONS(PNB_EGL_MEMBER)
#undef PNB_EGL_MEMBER
  // Extensions; null when the library lacks them.
  PFNEGLQUERYDEVICESEXTPROC QueryDevicesEXT = nullptr;
  PFNEGLQUERYDEVICESTRINGEXTPROC QueryDeviceStringEXT = nullptr;
  PFNEGLGETPLATFORMDISPLAYEXTPROC GetPlatformDisplayEXT = nullptr;
};

/// The library to load: `requested`, else $PNB_EGL_LIBRARY, else "libEGL.so.1".
std::string egl_library_name(const std::string& requested);

/// Loads the EGL library `name` once per process (drivers are never unloaded: several do not
/// survive dlclose). Throws Error(backend_unavailable) naming the library and dlerror().
const EglApi& load_egl(const std::string& name);

/// True when the space-separated `list` holds `name` exactly.
bool has_extension(const std::string& list, const char* name);

/// "EGL_BAD_MATCH (0x3009)" for an EGL error code.
std::string egl_error_text(EGLint code);

/// A device handle with what EGL says about it.
struct EglDevice {
  EGLDeviceEXT handle = nullptr;
  EglDeviceInfo info;
};

/// Every device of EGL_EXT_device_enumeration; empty when the library lacks the extension.
std::vector<EglDevice> query_devices(const EglApi& egl);

}  // namespace penumbra::render::gpu
