// render/src/tet_order.h -- a cache-friendly order of a mesh's tets
#pragma once
#include <cstdint>
#include <vector>

#include "penumbra/render/tet_mesh.h"

namespace penumbra::render::detail {

/// Tet ids sorted by the Morton code (21 bits per axis) of their centroids: tets close in space
/// end up close in memory, so rays walking through a region touch few cache lines whatever the
/// input ordering.
std::vector<std::int32_t> morton_order(const TetMesh& mesh);

}  // namespace penumbra::render::detail
