// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/gpu_info.cpp -- descriptions of the GPU backend's state (with or without EGL)
#include "penumbra/render/gpu_ray_caster.h"

namespace penumbra::render {

std::string GpuDeviceInfo::summary() const {
  return device + (software ? " [software rasteriser]" : "") + ": " + gl_renderer + ", OpenGL " + gl_version;
}

double GpuMemoryStats::mesh_bytes_per_tet() const {
  return tets ? static_cast<double>(geometry_bytes + adjacency_bytes + scalar_bytes) / static_cast<double>(tets) : 0.0;
}

double GpuMemoryStats::total_bytes_per_tet() const {
  return tets ? static_cast<double>(geometry_bytes + adjacency_bytes + scalar_bytes + acceleration_bytes) /
                    static_cast<double>(tets)
              : 0.0;
}

}  // namespace penumbra::render
