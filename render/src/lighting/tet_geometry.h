// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/tet_geometry.h -- small exact-as-possible tet helpers shared by the solver
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "penumbra/render/tet_mesh.h"

namespace penumbra::render::lighting {

/// Barycentric coordinates of p in tet t by signed volumes (sum to 1 up to rounding).
inline std::array<double, 4> barycentric(const TetMesh& mesh, std::int32_t t, const Vec3d& p) {
  const auto& tv = mesh.tets[static_cast<std::size_t>(t)];
  Vec3d q[4];
  for (int k = 0; k < 4; ++k) q[k] = mesh.points[static_cast<std::size_t>(tv[k])];
  const double inv = 1.0 / signed_volume6(q[0], q[1], q[2], q[3]);
  return {signed_volume6(p, q[1], q[2], q[3]) * inv, signed_volume6(q[0], p, q[2], q[3]) * inv,
          signed_volume6(q[0], q[1], p, q[3]) * inv, signed_volume6(q[0], q[1], q[2], p) * inv};
}

/// Gradient of the linear function with values v[k] at the corners p[k] of a tet: solves
/// e_i . g = v_i - v_0 (e_i = p_i - p_0) by the adjugate.
inline Vec3d linear_gradient(const Vec3d p[4], const double v[4]) {
  const Vec3d e1 = p[1] - p[0], e2 = p[2] - p[0], e3 = p[3] - p[0];
  const double inv = 1.0 / dot(e1, cross(e2, e3));
  return (cross(e2, e3) * (v[1] - v[0]) + cross(e3, e1) * (v[2] - v[0]) + cross(e1, e2) * (v[3] - v[0])) * inv;
}

/// Barycentric weights clamped to >= 0 and renormalised: interpolation stays a convex
/// combination even for a point a rounding error outside the tet.
inline std::array<double, 4> convex_weights(std::array<double, 4> w) {
  double sum = 0;
  for (double& x : w) {
    x = x > 0 ? x : 0;
    sum += x;
  }
  if (!(sum > 0)) return {0.25, 0.25, 0.25, 0.25};
  for (double& x : w) x /= sum;
  return w;
}

/// True when the segment p0 + t (p1 - p0), t in [0, 1], meets the closed box.
inline bool segment_meets_box(const Vec3d& p0, const Vec3d& p1, const Bounds& box) {
  double t0 = 0.0, t1 = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double d = p1[a] - p0[a];
    if (d == 0.0) {
      if (p0[a] < box.lo[a] || p0[a] > box.hi[a]) return false;
      continue;
    }
    double ta = (box.lo[a] - p0[a]) / d, tb = (box.hi[a] - p0[a]) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

inline bool inside_box(const Vec3d& p, const Bounds& box) {
  return p.x >= box.lo.x && p.x <= box.hi.x && p.y >= box.lo.y && p.y <= box.hi.y && p.z >= box.lo.z &&
         p.z <= box.hi.z;
}

/// Values below this are stored as exact zeros: far below anything visible, and it keeps
/// denormals (slow on most CPUs) out of the sweeps.
inline constexpr double kFlushToZero = 1e-30;
inline double flush(double v) { return v < kFlushToZero ? 0.0 : v; }

}  // namespace penumbra::render::lighting
