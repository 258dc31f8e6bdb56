// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/gpu_pre_illumination_grid.cpp -- the object-space grid the GPU cone tracer
// fills: the same nodes and the same clamped trilinear sampling as PreIlluminationVolume, so both
// paths give the same field for the same bounds and resolution. Compiled with and without EGL.
#include <algorithm>
#include <cmath>
#include <string>

#include "node_grid.h"
#include "penumbra/core/error.h"
#include "occlusion/gpu_occlusion.h"

namespace penumbra::render {

GpuPreIllumination gpu_pre_illumination_grid(const Bounds& bounds, int resolution) {
  require(resolution >= 2, "GpuConeTracer::pre_illumination: resolution = " + std::to_string(resolution) + "; expected >= 2");
  require(!bounds.empty() && std::isfinite(bounds.diagonal()),
          "GpuConeTracer::pre_illumination: bounds are empty or not finite");
  GpuPreIllumination g;
  g.lo = bounds.lo;
  detail::node_grid(bounds.hi - bounds.lo, resolution, g.dims, g.spacing);
  const std::size_t count = static_cast<std::size_t>(g.dims[0]) * g.dims[1] * g.dims[2];
  require(count < (std::size_t{1} << 31), "GpuConeTracer::pre_illumination: resolution " + std::to_string(resolution) +
                                              " gives " + std::to_string(count) + " nodes, beyond 32-bit indices");
  g.values.assign(count, 1.0f);
  return g;
}

double GpuPreIllumination::sample(const Vec3d& p) const {
  return values.empty() ? 1.0 : detail::sample_clamped(dims, lo, spacing, values, p);
}

}  // namespace penumbra::render
