// render/src/walk_mesh.h -- the mesh as the CPU walk reads it
#pragma once
#include <cstdint>

namespace penumbra::render::detail {

/// Face k (opposite vertex k) listed with its normal pointing out of a positive tet.
constexpr int kFaceVertices[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

/// A tet for the walk: its points and, per face, the neighbour as (tet << 2 | face index of the
/// shared face in the neighbour), or -1 on the boundary. 32 bytes: two per cache line.
struct WalkTet {
  std::int32_t v[4];
  std::int32_t next[4];
};

/// A boundary face, its vertices in outward order, and the walk tet it belongs to.
struct BoundaryTriangle {
  std::int32_t v[3];  // outward order
  std::int32_t tet, face;
};

}  // namespace penumbra::render::detail
