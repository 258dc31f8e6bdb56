// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/egl_loader.cpp -- dlopen of libEGL and device enumeration
#include "egl_loader.h"

#include <dlfcn.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>

#include "penumbra/core/error.h"

namespace penumbra::render::gpu {
namespace {

template <class F>
F symbol(void* lib, const char* name) {
  return reinterpret_cast<F>(dlsym(lib, name));
}

std::unique_ptr<EglApi> open_egl(const std::string& name) {
  // RTLD_LOCAL: the driver's symbols stay out of the host program's namespace.
  void* lib = dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (lib == nullptr) {
    const char* why = dlerror();
    throw Error(ErrorCode::backend_unavailable,
                "GPU backend: cannot load the EGL library '" + name + "' (" + (why ? why : "unknown reason") +
                    "); install libegl1 and a driver (Mesa: libegl-mesa0, NVIDIA: the driver's EGL) or set "
                    "PNB_EGL_LIBRARY, or use the cpu backend");
  }
  auto api = std::make_unique<EglApi>();
  api->library_path = name;
  bool complete = true;
#define PNB_EGL_LOAD(type, name)          \
  api->name = symbol<type>(lib, "egl" #name); \
  complete = complete && api->name != nullptr;
  PNB_EGL_FUNCTIONS(PNB_EGL_LOAD)
#undef PNB_EGL_LOAD
  if (!complete)
    throw Error(ErrorCode::backend_unavailable,
                "GPU backend: '" + name + "' is not an EGL 1.4 library (core entry points missing)");
  const char* ext = api->QueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  api->client_extensions = ext ? ext : "";
  api->QueryDevicesEXT = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(api->GetProcAddress("eglQueryDevicesEXT"));
  api->QueryDeviceStringEXT =
      reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(api->GetProcAddress("eglQueryDeviceStringEXT"));
  api->GetPlatformDisplayEXT =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(api->GetProcAddress("eglGetPlatformDisplayEXT"));
  return api;
}

}  // namespace

std::string egl_library_name(const std::string& requested) {
  if (!requested.empty()) return requested;
  const char* env = std::getenv("PNB_EGL_LIBRARY");
  if (env != nullptr && *env != '\0') return env;
  return "libEGL.so.1";
}

const EglApi& load_egl(const std::string& name) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<EglApi>> loaded;
  std::lock_guard lock(mutex);
  auto it = loaded.find(name);
  if (it != loaded.end()) return *it->second;
  auto api = open_egl(name);
  return *loaded.emplace(name, std::move(api)).first->second;
}

bool has_extension(const std::string& list, const char* name) {
  std::istringstream in(list);
  std::string word;
  while (in >> word)
    if (word == name) return true;
  return false;
}

std::string egl_error_text(EGLint code) {
  const char* name = "unknown EGL error";
  switch (code) {
    case EGL_SUCCESS: name = "EGL_SUCCESS"; break;
    case EGL_NOT_INITIALIZED: name = "EGL_NOT_INITIALIZED"; break;
    case EGL_BAD_ACCESS: name = "EGL_BAD_ACCESS"; break;
    case EGL_BAD_ALLOC: name = "EGL_BAD_ALLOC"; break;
    case EGL_BAD_ATTRIBUTE: name = "EGL_BAD_ATTRIBUTE"; break;
    case EGL_BAD_CONFIG: name = "EGL_BAD_CONFIG"; break;
    case EGL_BAD_CONTEXT: name = "EGL_BAD_CONTEXT"; break;
    case EGL_BAD_DISPLAY: name = "EGL_BAD_DISPLAY"; break;
    case EGL_BAD_MATCH: name = "EGL_BAD_MATCH"; break;
    case EGL_BAD_PARAMETER: name = "EGL_BAD_PARAMETER"; break;
    default: break;
  }
  char hex[16];
  std::snprintf(hex, sizeof hex, "0x%04x", static_cast<unsigned>(code));
  return std::string(name) + " (" + hex + ")";
}

std::vector<EglDevice> query_devices(const EglApi& egl) {
  std::vector<EglDevice> out;
  if (!egl.QueryDevicesEXT || !egl.QueryDeviceStringEXT) return out;
  EGLint count = 0;
  if (!egl.QueryDevicesEXT(0, nullptr, &count) || count <= 0) return out;
  std::vector<EGLDeviceEXT> handles(static_cast<std::size_t>(count));
  if (!egl.QueryDevicesEXT(count, handles.data(), &count)) return out;
  handles.resize(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < handles.size(); ++i) {
    EglDevice d;
    d.handle = handles[i];
    d.info.index = static_cast<int>(i);
    const char* ext = egl.QueryDeviceStringEXT(d.handle, EGL_EXTENSIONS);
    d.info.extensions = ext ? ext : "";
    if (has_extension(d.info.extensions, "EGL_EXT_device_drm")) {
      const char* file = egl.QueryDeviceStringEXT(d.handle, EGL_DRM_DEVICE_FILE_EXT);
      d.info.drm_file = file ? file : "";
    }
#ifdef EGL_DRM_RENDER_NODE_FILE_EXT
    if (has_extension(d.info.extensions, "EGL_EXT_device_drm_render_node")) {
      const char* node = egl.QueryDeviceStringEXT(d.handle, EGL_DRM_RENDER_NODE_FILE_EXT);
      d.info.render_node = node ? node : "";
    }
#endif
    d.info.software = has_extension(d.info.extensions, "EGL_MESA_device_software");
    out.push_back(std::move(d));
  }
  return out;
}

}  // namespace penumbra::render::gpu
