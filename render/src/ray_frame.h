// SPDX-License-Identifier: BSD-3-Clause
// render/src/ray_frame.h -- ray-centred projection and consistent edge orientation tests
//
// Every mesh point is projected onto the plane orthogonal to the ray (coordinates along u and v,
// with u x v = d) and given its depth along d. Whether the ray passes through a triangle then
// only depends on the signs of the 2D cross products e(a, b) = q_a x q_b of its three edges
// (e(a, b) is the Plücker permuted inner product of the ray and the edge a->b). Two rules make
// the traversal watertight:
//   1. Every tet sharing an edge sees exactly the same number for it, up to the sign its
//      direction gives: e = a.x * b.y - a.y * b.x is exactly antisymmetric, e(b, a) == -e(a, b)
//      bit for bit, because the two products commute exactly and round-to-nearest subtraction is
//      symmetric. That holds only with the products rounded separately: the render library is
//      compiled with -ffp-contract=off, since a fused multiply-add would round one product only.
//      (Computing each edge from its smaller point id would not need that, but the choice is a
//      branch the processor mispredicts about one time in three along a walk.)
//   2. An exactly zero value (the ray hits the edge's line) is decided by simulation of
//      simplicity: the ray is displaced by (eps, eps^2) along (u, v), eps -> 0+, which gives
//      sign(e) = -sign(dy), else sign(dx), with dx, dy taken from the endpoint with the smaller
//      point id. This is a single consistent perturbation of the ray, so through a vertex or
//      along an edge or a face plane the walk behaves as for a nearby generic ray: no segment
//      lost or doubled. Only an edge parallel to the ray keeps sign 0.
#pragma once
#include <cmath>
#include <cstdint>

#include "penumbra/core/vec3.h"

namespace penumbra::render::detail {

/// A projected point: ray-plane coordinates and depth along the ray.
struct Projected {
  double x, y, depth;
};

/// Orthonormal frame around a unit ray direction.
struct RayFrame {
  Vec3d origin, d, u, v;

  RayFrame() = default;
  RayFrame(const Vec3d& o, const Vec3d& unit_dir) : origin(o), d(unit_dir) {
    // Duff et al., "Building an orthonormal basis, revisited" (2017): branch-free, u x v = d.
    const double sign = std::copysign(1.0, d.z);
    const double a = -1.0 / (sign + d.z);
    const double b = d.x * d.y * a;
    u = {1.0 + sign * d.x * d.x * a, sign * b, -sign * d.x};
    v = {b, sign + d.y * d.y * a, -d.y};
  }

  Projected project(const Vec3d& p) const {
    const Vec3d r = p - origin;
    return {dot(r, u), dot(r, v), dot(r, d)};
  }
};

/// e(a, b) = q_a x q_b, exactly antisymmetric in a and b (rule 1 above).
inline double edge_value(const Projected& a, const Projected& b) { return a.x * b.y - a.y * b.x; }

/// Sign of e(a, b) with the simulation-of-simplicity tie rule (see the file comment).
inline int edge_sign(double value, const Projected& a, std::int32_t ia, const Projected& b, std::int32_t ib) {
  if (value > 0) return 1;
  if (value < 0) return -1;
  const bool forward = ia <= ib;
  const Projected& p = forward ? a : b;
  const Projected& q = forward ? b : a;
  const double dy = q.y - p.y, dx = q.x - p.x;
  int s = dy != 0 ? (dy > 0 ? -1 : 1) : (dx != 0 ? (dx > 0 ? 1 : -1) : 0);
  return forward ? s : -s;
}

/// edge_sign(...) > 0 without a data-dependent branch in the common case (value != 0): the
/// walk evaluates three per step and their signs are unpredictable.
inline bool edge_positive(double value, const Projected& a, std::int32_t ia, const Projected& b, std::int32_t ib) {
  bool positive = value > 0;
  if (value == 0) [[unlikely]]
    positive = edge_sign(value, a, ia, b, ib) > 0;
  return positive;
}

}  // namespace penumbra::render::detail
