// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/gpu_mesh_layout.h -- a TetMesh packed into the shader storage buffers' layout
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "penumbra/core/local_frame.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::render::gpu {

/// A BVH node as the shader reads it (std430, 32 bytes): inner nodes have count 0 and their
/// children at first and first + 1; leaves cover triangles [first, first + count).
struct BvhNode {
  float lo[3];
  std::int32_t first;
  float hi[3];
  std::int32_t count;
};
static_assert(sizeof(BvhNode) == 32);

/// Everything the ray-casting shader reads about a mesh, in float32 and int32.
struct GpuMeshLayout {
  /// Points, boxes and every length are in the mesh's local frame (TetMesh::frame), so float32
  /// keeps the precision of the mesh's own size wherever it sits and whatever its size.
  LocalFrame frame;
  double diagonal = 0;                                   ///< of the bounds, in the frame
  std::vector<float> points;                             ///< x, y, z per point
  std::vector<std::array<std::int32_t, 4>> tet_vertices; ///< point ids, tets in Morton order
  /// Per face k: (neighbour << 2 | index of the shared face in the neighbour), -1 on the boundary.
  std::vector<std::array<std::int32_t, 4>> tet_next;
  /// Boundary triangles, outward vertex order, then (tet << 2 | face); in the mesh's boundary
  /// order (what moved points keep) and in BVH leaf order (what the shader reads).
  std::vector<std::array<std::int32_t, 4>> boundary;
  std::vector<std::array<std::int32_t, 4>> triangles;
  std::vector<BvhNode> nodes;
};

/// Packs `mesh`: tets reordered along a Morton curve of their centroids (neighbouring rays
/// touch nearby memory), boundary faces under a BVH of median splits. Throws
/// Error(invalid_argument) when the mesh exceeds the int32 indexing (2^29 tets).
GpuMeshLayout build_gpu_mesh_layout(const TetMesh& mesh);

/// Re-places `layout` at the points of `moved`, the same mesh with its points moved
/// (move_tet_mesh): frame, diagonal, points, the BVH and the triangles' leaf order. The tets, their
/// adjacency and their Morton order (of the first positions: only locality depends on it) are kept.
void place_gpu_mesh_points(const TetMesh& moved, GpuMeshLayout& layout);

}  // namespace penumbra::render::gpu
