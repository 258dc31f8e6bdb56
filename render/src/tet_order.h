// SPDX-License-Identifier: BSD-3-Clause
// render/src/tet_order.h -- cache-friendly orders of a mesh's tets and points
#pragma once
#include <cstdint>
#include <vector>

#include "penumbra/render/tet_mesh.h"

namespace penumbra::render::detail {

/// Tet ids sorted by the Morton code (21 bits per axis) of their centroids: tets close in space
/// end up close in memory, so rays walking through a region touch few cache lines whatever the
/// input ordering.
std::vector<std::int32_t> morton_order(const TetMesh& mesh);

/// Point ids sorted by the Morton code of the points (same code as morton_order).
std::vector<std::int32_t> morton_point_order(const TetMesh& mesh);

/// The mesh with its points renumbered: point i of the result is point order[i] of `mesh` (order
/// a permutation, e.g. morton_point_order), the tets' point ids mapped alike. Tets, neighbours,
/// boundary faces and bounds are unchanged; the boundary surface is left out (it names the old
/// ids).
TetMesh with_points_in_order(const TetMesh& mesh, const std::vector<std::int32_t>& order);

}  // namespace penumbra::render::detail
