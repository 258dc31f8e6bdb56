// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/tet_mesh.h
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "penumbra/core/local_frame.h"
#include "penumbra/core/mesh_view.h"
#include "penumbra/core/vec3.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::render {

class BoundarySurface;

/// A boundary face: face `face` (the one opposite vertex `face`) of tet `tet`.
struct BoundaryFace {
  std::int32_t tet;
  std::int32_t face;
};

/// A render-ready, owned tetrahedral mesh prepared from a MeshView: non-tet cells split
/// conformingly (each quad face takes the diagonal through its smallest global vertex id),
/// every tet positively oriented, face adjacency built, duplicate points welded for adjacency.
///
/// `tets` keep the caller's original point ids, so per-point field values index them directly;
/// adjacency is built on welded ids, so coincident duplicate points do not make false internal
/// boundaries. Immutable after preparation; safe to share between threads for reading.
struct TetMesh {
  std::vector<Vec3d> points;                          ///< copy of the caller's points
  std::vector<std::array<std::int32_t, 4>> tets;      ///< original point ids, positive volume
  std::vector<std::array<std::int32_t, 4>> neighbors; ///< tet across the face opposite vertex k, -1 on the boundary
  std::vector<std::int64_t> source_cell;              ///< input cell each tet came from
  std::vector<BoundaryFace> boundary;                 ///< unmatched faces
  Bounds bounds;
  LocalFrame frame;                  ///< where float32 copies of the mesh live (the GPU paths)
  std::size_t welded_points = 0;     ///< duplicate points merged for adjacency
  /// The merged points as (point, the first point at its coordinates), for move_tet_mesh.
  std::vector<std::array<std::int32_t, 2>> welds;
  std::size_t reoriented_tets = 0;   ///< input tets whose orientation was flipped
  /// The tets' total volume and the volume the boundary faces enclose (divergence theorem). They
  /// agree to rounding for a valid tessellation; where they differ, the mesh is tangled (cells
  /// folded over or through each other, e.g. a crushed shell) and pictures through its overlaps
  /// are undefined. (Agreement does not prove a mesh untangled: separate overlapping parts agree.)
  double tet_volume = 0, enclosed_volume = 0;
  bool tangled() const;
  std::uint64_t topology_version = 0;
  /// OpenMesh boundary surface (entry/exit, geometry) at preparation; move_tet_mesh shares it.
  std::shared_ptr<const BoundarySurface> surface;

  std::size_t tet_count() const { return tets.size(); }
};

/// Prepares `mesh` for rendering; validates it first (see validate_mesh) and throws
/// penumbra::Error(invalid_argument) naming the offending cell or point. `call` prefixes errors.
TetMesh prepare_tet_mesh(const MeshView& mesh, const char* call = "prepare_tet_mesh");

/// The smallest altitude of the mesh's tets (a vertex's distance from the plane of the face
/// opposite it): how thin the thinnest cell is. Moving every point by less than a quarter of it
/// cannot invert a cell, to first order in the motion.
double smallest_altitude(const TetMesh& mesh);

/// Whether the points of `moved` (the mesh of `prepared` with its points moved) keep every weld
/// of `prepared`: the points merged for adjacency still coincide. When they do not (an interface
/// that opened), the mesh's adjacency changed and it must be prepared anew.
bool keeps_welds(const TetMesh& prepared, const MeshView& moved);

/// `prepared` with the point coordinates of `moved`, the same mesh a step later in a Lagrangian
/// or ALE code: what depends on the connectivity alone (the split into tets, their orientation,
/// the adjacency, the boundary faces, the welds, the boundary surface, whose OpenMesh points stay
/// those of the preparation) is kept; the bounds, the frame and the volumes follow the points. Throws penumbra::Error(invalid_argument) for a NaN or
/// infinite coordinate or an extent beyond validate_mesh's limits, and naming the input cell
/// when the motion inverted or flattened one of its tets; requires keeps_welds(prepared, moved)
/// and the same point count. `call` prefixes errors.
TetMesh move_tet_mesh(const TetMesh& prepared, const MeshView& moved, const char* call = "move_tet_mesh");

}  // namespace penumbra::render

PNB_PUBLIC_END
