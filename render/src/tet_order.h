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

}  // namespace penumbra::render::detail
