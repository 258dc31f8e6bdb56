// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/ghost_cells.h -- a published mesh without its ghost cells (vtkGhostType)
#pragma once
#include <cstdint>
#include <vector>

#include "penumbra/core/mesh_view.h"

namespace penumbra::insitu {

/// The cells of a mesh that are not ghosts, in owned arrays, over the mesh's own points (a point
/// used by ghost cells alone stays, unused).
struct OwnCells {
  std::vector<std::int64_t> connectivity, offsets;
  std::vector<std::uint8_t> types;
  MeshView view;  ///< over the arrays above and the mesh's points; valid while this lives and is not copied
};

/// `mesh` (validated) without the cells marked ghost (MeshView::ghost). The cells keep their
/// order, so cell k of the result is the k-th cell that is not a ghost.
OwnCells without_ghosts(const MeshView& mesh);

}  // namespace penumbra::insitu
