// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/egl_device.h -- headless EGL devices and which one to use
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::render {

/// One EGL device as EGL_EXT_device_enumeration lists it.
struct EglDeviceInfo {
  int index = 0;            ///< position in EGL's device list
  std::string extensions;   ///< the device extension string
  std::string drm_file;     ///< DRM device file (EGL_EXT_device_drm), empty if none
  std::string render_node;  ///< DRM render node (EGL_EXT_device_drm_render_node), empty if none
  bool software = false;    ///< a CPU rasteriser (EGL_MESA_device_software, e.g. llvmpipe)
  /// A GPU: not a software device and backed by a DRM node or a CUDA device.
  bool hardware() const;
  /// "EGL device 1 (/dev/dri/renderD128, hardware)".
  std::string describe() const;
};

/// How the GPU backend finds EGL and picks a device. Empty/negative fields fall back to the
/// environment, so a job script can steer a compiled program:
///   PNB_EGL_LIBRARY  path or soname of libEGL (default libEGL.so.1)
///   PNB_EGL_DEVICE   index into the EGL device list, or "surfaceless" for Mesa's surfaceless platform
struct GpuOptions {
  std::string egl_library;          ///< empty: $PNB_EGL_LIBRARY, else "libEGL.so.1"
  std::string device;               ///< empty: $PNB_EGL_DEVICE, else automatic (see select_egl_device, node_local_rank)
  bool require_hardware = false;    ///< refuse software devices (llvmpipe)
  /// Largest total buffer size the caster may allocate on the device; 0 = the device's own limits.
  std::size_t memory_limit_bytes = 0;
  /// Receives the one-line log messages (chosen device, GL version, renderer); empty = stderr.
  std::function<void(const std::string&)> log;
};

/// The device choice: an index into the device list, or -1 for Mesa's surfaceless platform.
/// `requested` is a device index ("0", "1", ...), "surfaceless", or empty for automatic: hardware
/// device number `local_rank` modulo their count (so the ranks on a multi-GPU node spread over
/// its GPUs), else the surfaceless platform (GpuDevice::open then falls back to the other listed
/// devices, e.g. Mesa's software device, if that platform is missing).
/// Throws Error(invalid_argument) for a malformed or out-of-range request and
/// Error(backend_unavailable) when `require_hardware` leaves nothing to choose.
int select_egl_device(const std::vector<EglDeviceInfo>& devices, const std::string& requested, bool require_hardware,
                      int local_rank = 0);

/// This process's rank among the MPI ranks on its node, from the launcher's environment
/// (OMPI_COMM_WORLD_LOCAL_RANK, MPI_LOCALRANKID, MV2_COMM_WORLD_LOCAL_RANK, SLURM_LOCALID), or 0.
int node_local_rank() noexcept;

/// The EGL devices of this node. Throws Error(backend_unavailable) with the reason when EGL
/// cannot be loaded or lacks device enumeration.
std::vector<EglDeviceInfo> list_egl_devices(const GpuOptions& options = {});

/// True when EGL lists a hardware device (never throws; false when EGL is missing).
bool hardware_gpu_present(const GpuOptions& options = {}) noexcept;

/// True when this build contains the EGL/OpenGL backend (PNB_ENABLE_EGL).
bool gpu_backend_compiled() noexcept;

}  // namespace penumbra::render

PNB_PUBLIC_END
