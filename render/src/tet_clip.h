// SPDX-License-Identifier: BSD-3-Clause
// render/src/tet_clip.h -- a line clipped against one tet, for the double-precision references
// (independent of adjacency and of the walk)
#pragma once
#include <cstdint>
#include <vector>

#include "bvh.h"
#include "penumbra/core/vec3.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::render::detail {

/// The line o + t d (unit d) with an orthonormal u, v across it, for the in-plane tie rule.
struct ClipLine {
  Vec3d o, d, u, v;
  ClipLine(const Vec3d& origin, const Vec3d& unit_dir);
};

/// Clips the line for t in [0, t_max] against tet `t` into [lo, hi]; false when that is empty or
/// a single point. A line lying exactly in a face plane is displaced by (eps u + eps^2 v), so of
/// the tets sharing that face (or edge) exactly one contains it.
bool clip_to_tet(const TetMesh& mesh, std::int32_t t, const ClipLine& line, double t_max, double& lo, double& hi);

/// A BVH over the tets' boxes (padded by 1e-9 of the bounds' diagonal, so a line grazing a face
/// is never lost to rounding), for "every tet along a line" before clip_to_tet.
Bvh tet_bvh(const TetMesh& mesh);

/// The scalar at x inside tet t by barycentric coordinates (NaN when a vertex is NaN).
double scalar_in_tet(const TetMesh& mesh, const std::vector<float>& scalars, std::int32_t t, const Vec3d& x);

}  // namespace penumbra::render::detail
