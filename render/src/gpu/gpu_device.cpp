// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/gpu_device.cpp -- a headless OpenGL 4.5 context on the chosen EGL device
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <string>

#include "gpu_device_impl.h"
#include "penumbra/core/error.h"

namespace penumbra::render {
namespace {

using gpu::EglApi;
using gpu::EglDevice;

// eglTerminate ends every context on a display, and displays are shared process-wide: the
// display is terminated only when its last context is gone.
std::mutex g_display_mutex;
std::map<EGLDisplay, int> g_display_users;

void release_display(const EglApi& egl, EGLDisplay display) {
  std::lock_guard lock(g_display_mutex);
  if (--g_display_users[display] == 0) {
    g_display_users.erase(display);
    egl.Terminate(display);
  }
}

// A display to try: a listed device, or Mesa's surfaceless platform (device == nullptr).
struct Candidate {
  const EglDevice* device = nullptr;
  std::string name;
};

bool software_renderer(const std::string& renderer) {
  for (const char* s : {"llvmpipe", "softpipe", "SwiftShader", "swrast"})
    if (renderer.find(s) != std::string::npos) return true;
  return false;
}

std::string gl_string(const gpu::GlApi& gl, GLenum name) {
  const auto* s = reinterpret_cast<const char*>(gl.GetString(name));
  return s ? s : "";
}

// Creates the context on one candidate display; throws Error(backend_unavailable) with the reason.
void open_on(GpuDevice::Impl& d, const Candidate& c) {
  const EglApi& egl = *d.egl;
  EGLDisplay display = EGL_NO_DISPLAY;
  if (c.device != nullptr)
    display = egl.GetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, c.device->handle, nullptr);
  else
    display = egl.GetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display == EGL_NO_DISPLAY)
    throw Error(ErrorCode::backend_unavailable, "no EGL display (" + gpu::egl_error_text(egl.GetError()) + ")");
  {
    std::lock_guard lock(g_display_mutex);
    EGLint major = 0, minor = 0;
    if (!egl.Initialize(display, &major, &minor))
      throw Error(ErrorCode::backend_unavailable, "eglInitialize failed (" + gpu::egl_error_text(egl.GetError()) + ")");
    ++g_display_users[display];
  }
  struct Guard {
    const EglApi& egl;
    EGLDisplay display;
    bool armed = true;
    ~Guard() {
      if (armed) release_display(egl, display);
    }
  } guard{egl, display};
  const char* ext_c = egl.QueryString(display, EGL_EXTENSIONS);
  const std::string ext = ext_c ? ext_c : "";
  if (!gpu::has_extension(ext, "EGL_KHR_surfaceless_context"))
    throw Error(ErrorCode::backend_unavailable, "the display lacks EGL_KHR_surfaceless_context");
  if (!egl.BindAPI(EGL_OPENGL_API))
    throw Error(ErrorCode::backend_unavailable, "the display offers no desktop OpenGL (eglBindAPI failed)");
  EGLConfig config = EGL_NO_CONFIG_KHR;
  if (!gpu::has_extension(ext, "EGL_KHR_no_config_context")) {
    const EGLint attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_NONE};
    EGLint n = 0;
    if (!egl.ChooseConfig(display, attribs, &config, 1, &n) || n < 1)
      throw Error(ErrorCode::backend_unavailable, "no EGL config for OpenGL (" + gpu::egl_error_text(egl.GetError()) + ")");
  }
  const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                    EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  EGLContext context = egl.CreateContext(display, config, EGL_NO_CONTEXT, context_attribs);
  if (context == EGL_NO_CONTEXT)
    throw Error(ErrorCode::backend_unavailable,
                "no OpenGL 4.5 core context (" + gpu::egl_error_text(egl.GetError()) + ")");
  d.display = display;
  d.context = context;
  guard.armed = false;  // ~Impl releases from here on
  gpu::CurrentContext current(d);
  d.gl = gpu::load_gl(egl);
  const gpu::GlApi& gl = d.gl;
  GLint major = 0, minor = 0;
  gl.GetIntegerv(GL_MAJOR_VERSION, &major);
  gl.GetIntegerv(GL_MINOR_VERSION, &minor);
  if (major * 10 + minor < 45)
    throw Error(ErrorCode::backend_unavailable,
                "the context is OpenGL " + std::to_string(major) + "." + std::to_string(minor) + "; 4.5 is needed");
  d.info.device = c.name;
  d.info.gl_version = gl_string(gl, GL_VERSION);
  d.info.gl_renderer = gl_string(gl, GL_RENDERER);
  d.info.gl_vendor = gl_string(gl, GL_VENDOR);
  d.info.software = (c.device != nullptr && c.device->info.software) || software_renderer(d.info.gl_renderer);
  GLint64 block = 0;
  gl.GetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &block);
  d.info.max_storage_block_bytes = block;
  GLint blocks = 0, groups = 0;
  gl.GetIntegerv(GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS, &blocks);
  gl.GetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0, &groups);
  d.max_compute_storage_blocks = blocks;
  d.max_work_group_count_x = groups;
  GLint extensions = 0;
  gl.GetIntegerv(GL_NUM_EXTENSIONS, &extensions);
  for (GLint i = 0; i < extensions; ++i) {
    const auto* e = reinterpret_cast<const char*>(gl.GetStringi(GL_EXTENSIONS, static_cast<GLuint>(i)));
    if (e != nullptr && std::string(e) == "GL_NVX_gpu_memory_info") {
      constexpr GLenum kAvailableKiB = 0x9049;  // GL_GPU_MEMORY_INFO_CURRENT_AVAILABLE_VIDMEM_NVX
      GLint kib = 0;
      gl.GetIntegerv(kAvailableKiB, &kib);
      d.info.free_memory_bytes = static_cast<std::int64_t>(kib) * 1024;
    }
  }
  while (gl.GetError() != GL_NO_ERROR) {
  }
}

}  // namespace

namespace gpu {

CurrentContext::CurrentContext(GpuDevice::Impl& device) : m_device(device), m_lock(device.mutex) {
  if (m_device.current_depth++ > 0) return;
  const EglApi& egl = *m_device.egl;
  m_previous_context = egl.GetCurrentContext();
  if (m_previous_context != EGL_NO_CONTEXT) {
    m_previous_display = egl.GetCurrentDisplay();
    m_previous_draw = egl.GetCurrentSurface(EGL_DRAW);
    m_previous_read = egl.GetCurrentSurface(EGL_READ);
  }
  if (!egl.MakeCurrent(m_device.display, EGL_NO_SURFACE, EGL_NO_SURFACE, m_device.context)) {
    --m_device.current_depth;
    throw Error(ErrorCode::backend_unavailable,
                "GPU backend: eglMakeCurrent failed (" + egl_error_text(egl.GetError()) + ")");
  }
}

CurrentContext::~CurrentContext() {
  if (--m_device.current_depth > 0) return;
  const EglApi& egl = *m_device.egl;
  if (m_previous_context != EGL_NO_CONTEXT && m_previous_context != m_device.context)
    egl.MakeCurrent(m_previous_display, m_previous_draw, m_previous_read, m_previous_context);
  else
    egl.MakeCurrent(m_device.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

}  // namespace gpu

GpuDevice::Impl::~Impl() {
  if (egl == nullptr || display == EGL_NO_DISPLAY) return;
  if (context != EGL_NO_CONTEXT) egl->DestroyContext(display, context);
  release_display(*egl, display);
}

GpuDevice::GpuDevice(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
GpuDevice::~GpuDevice() = default;
const GpuDeviceInfo& GpuDevice::info() const { return m_impl->info; }
const GpuOptions& GpuDevice::options() const { return m_impl->options; }

std::shared_ptr<GpuDevice> GpuDevice::open(const GpuOptions& options) {
  auto d = std::make_unique<Impl>();
  d->options = options;
  if (d->options.device.empty()) {
    const char* env = std::getenv("PNB_EGL_DEVICE");
    if (env != nullptr) d->options.device = env;
  }
  d->egl = &gpu::load_egl(gpu::egl_library_name(options.egl_library));
  const EglApi& egl = *d->egl;
  if (!egl.GetPlatformDisplayEXT)
    throw Error(ErrorCode::backend_unavailable,
                "GPU backend: '" + egl.library_path + "' lacks EGL_EXT_platform_base; a headless context needs it");
  const bool device_platform = gpu::has_extension(egl.client_extensions, "EGL_EXT_platform_device");
  const bool surfaceless_platform = gpu::has_extension(egl.client_extensions, "EGL_MESA_platform_surfaceless");
  const std::vector<EglDevice> devices = device_platform ? gpu::query_devices(egl) : std::vector<EglDevice>{};
  std::vector<EglDeviceInfo> infos;
  for (const auto& dev : devices) infos.push_back(dev.info);
  const int chosen = select_egl_device(infos, d->options.device, d->options.require_hardware, node_local_rank());

  // The chosen display first; when the choice was automatic, the others in order of preference
  // after it (a node whose first GPU is busy or misconfigured still renders).
  std::vector<Candidate> order;
  auto add = [&](int index) {
    for (const auto& c : order)
      if ((c.device == nullptr && index < 0) || (c.device != nullptr && c.device->info.index == index)) return;
    if (index < 0) {
      if (surfaceless_platform) order.push_back({nullptr, "Mesa surfaceless platform"});
    } else {
      const EglDevice& dev = devices[static_cast<std::size_t>(index)];
      order.push_back({&dev, dev.info.describe()});
    }
  };
  add(chosen);
  if (d->options.device.empty()) {
    for (const auto& dev : devices)
      if (dev.info.hardware()) add(dev.info.index);
    if (!d->options.require_hardware) {
      for (const auto& dev : devices) add(dev.info.index);
      add(-1);
    }
  }
  if (order.empty())
    throw Error(ErrorCode::backend_unavailable, "GPU backend: '" + egl.library_path +
                                                    "' offers neither EGL devices (EGL_EXT_platform_device) nor Mesa's "
                                                    "surfaceless platform");
  std::string failures;
  for (const Candidate& c : order) {
    try {
      open_on(*d, c);
      auto device = std::shared_ptr<GpuDevice>(new GpuDevice(std::move(d)));
      const std::string line = "GPU backend on " + device->info().summary();
      if (device->options().log) device->options().log(line);
      else std::fprintf(stderr, "penumbra: %s\n", line.c_str());
      return device;
    } catch (const Error& e) {
      failures += (failures.empty() ? "" : "; ") + c.name + ": " + e.what();
      // A half-made context is cleaned up before the next try.
      if (d->context != EGL_NO_CONTEXT) d->egl->DestroyContext(d->display, d->context);
      if (d->display != EGL_NO_DISPLAY) release_display(*d->egl, d->display);
      d->context = EGL_NO_CONTEXT;
      d->display = EGL_NO_DISPLAY;
    }
  }
  throw Error(ErrorCode::backend_unavailable, "GPU backend: no usable OpenGL 4.5 context: " + failures);
}

std::vector<EglDeviceInfo> list_egl_devices(const GpuOptions& options) {
  const EglApi& egl = gpu::load_egl(gpu::egl_library_name(options.egl_library));
  if (!egl.QueryDevicesEXT)
    throw Error(ErrorCode::backend_unavailable,
                "GPU backend: '" + egl.library_path + "' lacks EGL_EXT_device_enumeration");
  std::vector<EglDeviceInfo> out;
  for (const auto& d : gpu::query_devices(egl)) out.push_back(d.info);
  return out;
}

bool hardware_gpu_present(const GpuOptions& options) noexcept {
  try {
    for (const auto& d : list_egl_devices(options))
      if (d.hardware()) return true;
  } catch (...) {
  }
  return false;
}

bool gpu_backend_compiled() noexcept { return true; }

}  // namespace penumbra::render
