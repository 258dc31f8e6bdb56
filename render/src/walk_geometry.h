// SPDX-License-Identifier: BSD-3-Clause
// render/src/walk_geometry.h -- how the walk sees the mesh from one ray: projected points and
// interpolation along the ray, per ray (any ray) or per frame (screen space)
//
// The walk only needs, for each point it meets, 2D coordinates in a plane across the ray (whose
// edge cross products decide every exit, see ray_frame.h) and a way to turn the barycentric
// weights of a crossing point into its depth and interpolation weights.
//   - RayGeometry projects each point onto the plane orthogonal to the ray. It works for any
//     ray, the eye inside the mesh included.
//   - ScreenGeometry uses coordinates computed once per frame: each point's position on the
//     image plane one unit in front of the eye, X = x/z and Y = y/z in the camera frame, and its
//     inverse depth 1/z; a pixel's ray is a point (sx, sy) of that plane. An edge's cross product
//     then equals the ray-plane one times the two points' positive depth factors, so it has the
//     same sign and the walk takes the same path; interpolation is perspective-correct (weights
//     divided by depth). Valid only when every point lies in front of the eye, and it saves the
//     per-step projection: the points are shared by all rays of the frame.
#pragma once
#include <cstdint>
#include <vector>

#include "penumbra/core/vec3.h"
#include "ray_frame.h"

namespace penumbra::render::detail {

/// Interpolation at a point of a face: mu (summing to 1) weighs the three vertices; t is the depth.
struct FacePoint {
  double mu[3];
  double t;
};

struct RayGeometry {
  const RayFrame& frame;
  const Vec3d* points;
  const std::int32_t* point_ids;  // the mesh's id of each point, which indexes `scalars`
  const float* scalars;
  /// Boundary faces come from the BVH along the ray.
  static constexpr bool kBinnedFaces = false;
  /// The entry face's projections are reused on the next tet (projecting costs more than
  /// matching ids).
  static constexpr bool kReuseFace = true;
  /// The ray may start inside the mesh: depths may be negative.
  static constexpr bool kInFront = false;

  Projected at(std::int32_t id) const { return frame.project(points[id]); }
  double scalar(std::int32_t id) const { return scalars[point_ids[id]]; }
  /// `w`: the vertices' unnormalised barycentric weights (sum > 0) in the ray plane.
  FacePoint interpolate(const double w[3], const Projected& a, const Projected& b, const Projected& c) const {
    const double inv = 1.0 / (w[0] + w[1] + w[2]);
    FacePoint p{{w[0] * inv, w[1] * inv, w[2] * inv}, 0.0};
    p.t = p.mu[0] * a.depth + p.mu[1] * b.depth + p.mu[2] * c.depth;
    return p;
  }
};

/// A point on the image plane: X = x/z, Y = y/z and 1/z in the camera frame, with the point's
/// scalar beside them so that a step reads one 32-byte record per point.
struct ScreenPoint {
  double x, y, inv_z, s;
};

/// A camera's frame for screen coordinates: right, down-screen (so that right x down = forward,
/// the same handedness as RayFrame's u x v = d) and forward.
struct ScreenBasis {
  Vec3d eye, right, down, forward;

  /// Screen coordinates of `p` (in front of the eye) with its scalar.
  ScreenPoint project(const Vec3d& p, double scalar) const {
    const Vec3d r = p - eye;
    const double z = dot(r, forward);
    const double inv_z = 1.0 / z;
    return {dot(r, right) * inv_z, dot(r, down) * inv_z, inv_z, scalar};
  }
};

struct ScreenGeometry {
  const ScreenPoint* points = nullptr;
  double sx = 0, sy = 0;  // the ray's point on the image plane
  double depth_scale = 0;  // distance along the unit ray per unit of camera depth: 1 / (d . forward)
  /// Boundary faces come from the frame's screen tiles: those facing the eye whose boxes hold a
  /// pixel centre of the ray's tile (a superset of the faces the ray enters through); from the
  /// BVH when faces_begin is null (a tile crowded with such faces, where the BVH's logarithmic
  /// search wins).
  static constexpr bool kBinnedFaces = true;
  const std::int32_t* faces_begin = nullptr;
  const std::int32_t* faces_end = nullptr;
  static constexpr bool kReuseFace = false;
  /// Every point lies in front of the eye: every depth is positive.
  static constexpr bool kInFront = true;

  ScreenGeometry() = default;
  ScreenGeometry(const ScreenPoint* pts, const ScreenBasis& basis, const Vec3d& unit_dir,
                 const std::int32_t* faces_first, const std::int32_t* faces_last)
      : points(pts), faces_begin(faces_first), faces_end(faces_last) {
    const double along = dot(unit_dir, basis.forward);
    sx = dot(unit_dir, basis.right) / along;
    sy = dot(unit_dir, basis.down) / along;
    depth_scale = 1.0 / along;
  }

  Projected at(std::int32_t id) const {
    const ScreenPoint& p = points[id];
    return {p.x - sx, p.y - sy, p.inv_z};
  }
  double scalar(std::int32_t id) const { return points[id].s; }
  FacePoint interpolate(const double w[3], const Projected& a, const Projected& b, const Projected& c) const {
    const double m[3] = {w[0] * a.depth, w[1] * b.depth, w[2] * c.depth};
    const double inv = 1.0 / (m[0] + m[1] + m[2]);
    // 1/z is linear on the image plane: z at the point is sum(w) / sum(w / z).
    return {{m[0] * inv, m[1] * inv, m[2] * inv}, (w[0] + w[1] + w[2]) * inv * depth_scale};
  }
};

}  // namespace penumbra::render::detail
