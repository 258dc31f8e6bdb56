// render/src/occlusion/gpu_pre_illumination_grid.cpp -- the object-space grid the GPU cone tracer
// fills: the same nodes and the same clamped trilinear sampling as PreIlluminationVolume, so both
// paths give the same field for the same bounds and resolution. Compiled with and without EGL.
#include <algorithm>
#include <cmath>
#include <string>

#include "penumbra/core/error.h"
#include "penumbra/render/gpu_occlusion.h"

namespace penumbra::render {

GpuPreIllumination gpu_pre_illumination_grid(const Bounds& bounds, int resolution) {
  require(resolution >= 2, "GpuConeTracer::pre_illumination: resolution = " + std::to_string(resolution) + "; expected >= 2");
  require(!bounds.empty() && std::isfinite(bounds.diagonal()),
          "GpuConeTracer::pre_illumination: bounds are empty or not finite");
  GpuPreIllumination g;
  const Vec3d ext = bounds.hi - bounds.lo;
  const double longest = std::max(ext.x, std::max(ext.y, ext.z));
  g.lo = bounds.lo;
  for (int a = 0; a < 3; ++a) {
    // As PreIlluminationVolume's constructor.
    g.dims[static_cast<std::size_t>(a)] =
        ext[a] > 0 ? std::max(2, static_cast<int>(std::ceil((resolution - 1) * ext[a] / longest - 1e-9)) + 1) : 2;
    g.spacing[a] = ext[a] > 0 ? ext[a] / (g.dims[static_cast<std::size_t>(a)] - 1) : 0.0;
  }
  const std::size_t count = static_cast<std::size_t>(g.dims[0]) * g.dims[1] * g.dims[2];
  require(count < (std::size_t{1} << 31), "GpuConeTracer::pre_illumination: resolution " + std::to_string(resolution) +
                                              " gives " + std::to_string(count) + " nodes, beyond 32-bit indices");
  g.values.assign(count, 1.0f);
  return g;
}

double GpuPreIllumination::sample(const Vec3d& p) const {
  if (values.empty()) return 1.0;
  int i[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const int n = dims[static_cast<std::size_t>(a)];
    double u = spacing[a] > 0 ? (p[a] - lo[a]) / spacing[a] : 0.0;
    if (!std::isfinite(u)) u = 0;
    u = std::clamp(u, 0.0, static_cast<double>(n - 1));
    i[a] = std::min(static_cast<int>(u), n - 2);
    f[a] = u - i[a];
  }
  double sum = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const int dx = corner & 1, dy = (corner >> 1) & 1, dz = corner >> 2;
    const double w = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
    sum += w * values[static_cast<std::size_t>(i[0] + dx) +
                      static_cast<std::size_t>(dims[0]) * (static_cast<std::size_t>(i[1] + dy) +
                                                           static_cast<std::size_t>(dims[1]) * static_cast<std::size_t>(i[2] + dz))];
  }
  return sum;
}

}  // namespace penumbra::render
