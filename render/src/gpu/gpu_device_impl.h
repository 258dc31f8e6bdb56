// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/gpu_device_impl.h -- the EGL context behind GpuDevice
#pragma once
#include <memory>
#include <mutex>

#include "egl_loader.h"
#include "gl_api.h"
#include "penumbra/render/gpu_ray_caster.h"

namespace penumbra::render {

struct GpuDevice::Impl {
  GpuOptions options;
  const gpu::EglApi* egl = nullptr;
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  gpu::GlApi gl;
  GpuDeviceInfo info;
  std::int64_t max_compute_storage_blocks = 0;
  std::int64_t max_work_group_count_x = 0;
  GLuint ray_cast_program = 0;  ///< compiled on first use, shared by the casters on this device
  std::recursive_mutex mutex;  ///< one thread at a time drives the context
  int current_depth = 0;       ///< nesting of CurrentContext on the owning thread

  ~Impl();
};

namespace gpu {

/// Holds the device's lock with its context current on this thread; releases both on exit so
/// that another thread may take the device next.
class CurrentContext {
public:
  explicit CurrentContext(GpuDevice::Impl& device);
  ~CurrentContext();
  CurrentContext(const CurrentContext&) = delete;
  CurrentContext& operator=(const CurrentContext&) = delete;
  const GlApi& gl() const { return m_device.gl; }

private:
  GpuDevice::Impl& m_device;
  std::unique_lock<std::recursive_mutex> m_lock;
  // Whatever the host program had current on this thread, restored afterwards.
  EGLDisplay m_previous_display = EGL_NO_DISPLAY;
  EGLContext m_previous_context = EGL_NO_CONTEXT;
  EGLSurface m_previous_draw = EGL_NO_SURFACE, m_previous_read = EGL_NO_SURFACE;
};

}  // namespace gpu
}  // namespace penumbra::render
