// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/node_grid.h -- the object-space grid's nodes and sampling, shared by
// PreIlluminationVolume and the GPU cone tracer's grid so both give the same field
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "penumbra/core/vec3.h"

namespace penumbra::render::detail {

/// `resolution` nodes along the longest side of a box of extent `ext`, the other sides in
/// proportion (at least 2 nodes each); spacing 0 along a flat side.
inline void node_grid(const Vec3d& ext, int resolution, std::array<int, 3>& dims, Vec3d& spacing) {
  const double longest = std::max(ext.x, std::max(ext.y, ext.z));
  for (int a = 0; a < 3; ++a) {
    const auto axis = static_cast<std::size_t>(a);
    dims[axis] = ext[a] > 0 ? std::max(2, static_cast<int>(std::ceil((resolution - 1) * ext[a] / longest - 1e-9)) + 1) : 2;
    spacing[a] = ext[a] > 0 ? ext[a] / (dims[axis] - 1) : 0.0;
  }
}

/// Trilinear interpolation of node values (index i + dims[0] * (j + dims[1] * k)) at p, clamped
/// to the grid.
inline double sample_clamped(const std::array<int, 3>& dims, const Vec3d& lo, const Vec3d& spacing,
                             const std::vector<float>& values, const Vec3d& p) {
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

}  // namespace penumbra::render::detail
