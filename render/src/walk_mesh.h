// SPDX-License-Identifier: BSD-3-Clause
// render/src/walk_mesh.h -- the mesh as the CPU walk reads it
#pragma once
#include <cstdint>
#include <vector>

#include "penumbra/render/tet_mesh.h"

namespace penumbra::render::detail {

/// Face k (opposite vertex k) listed with its normal pointing out of a positive tet.
constexpr int kFaceVertices[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

/// Entered through face k, the other vertices A, B, C are ordered so that the three candidate
/// exit faces, listed outward, are (D,A,B), (D,B,C), (D,C,A) with D the vertex k: (k,A,B,C) is an
/// odd permutation of (0,1,2,3), like (3,0,1,2).
constexpr int kAbc[4][3] = {{1, 3, 2}, {0, 2, 3}, {1, 0, 3}, {0, 1, 2}};

/// The exit face (D,X,Y) by the signs of e(D,A), e(D,B), e(D,C) (bit j - 1 set: e(D, vertex j) > 0,
/// positions A = 1, B = 2, C = 3): the exit is (D,A,B) iff e(D,A) > 0 >= e(D,B), and cyclically;
/// exactly one holds for any consistent sign pattern (the entry face's own edges are known to be
/// on the inside), so a table replaces the hard-to-predict branches. Patterns 0 and 7 cannot
/// occur with consistent signs (the ray would have to pass exactly through D, which the tie rule
/// excludes); they fall back to (D,A,B). The table gives X's position; Y is the next (3, then 1).
constexpr int kExitX[8] = {1, 1, 2, 2, 3, 1, 3, 1};

/// A tet for the walk: its points and, per face, the neighbour as (tet << 2 | face index of the
/// shared face in the neighbour), or -1 on the boundary. 32 bytes: two per cache line.
struct WalkTet {
  std::int32_t v[4];
  std::int32_t next[4];
};

/// The mesh's tets as walk records, record i holding tet order[i] (order: a permutation of the
/// tet ids, e.g. morton_order), with the neighbours renumbered to record positions.
std::vector<WalkTet> walk_tets(const TetMesh& mesh, const std::vector<std::int32_t>& order);

/// A boundary face, its vertices in outward order, and the walk tet it belongs to.
struct BoundaryTriangle {
  std::int32_t v[3];  // outward order
  std::int32_t tet, face;
};

}  // namespace penumbra::render::detail
