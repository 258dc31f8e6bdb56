// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/ghost_cells.cpp -- a published mesh without its ghost cells
#include "ghost_cells.h"

namespace penumbra::insitu {

OwnCells without_ghosts(const MeshView& mesh) {
  OwnCells own;
  own.offsets.push_back(0);
  for (std::size_t c = 0; c < mesh.cell_count(); ++c) {
    if (mesh.ghost(c)) continue;
    const std::int64_t begin = mesh.cell_begin(c), n = cell_point_count(mesh.cell_type(c));
    for (std::int64_t k = 0; k < n; ++k) own.connectivity.push_back(mesh.connectivity[static_cast<std::size_t>(begin + k)]);
    own.offsets.push_back(static_cast<std::int64_t>(own.connectivity.size()));
    own.types.push_back(mesh.cell_type(c));
  }
  own.view = mesh;
  own.view.connectivity = {own.connectivity.data(), own.connectivity.size(), ScalarType::int64};
  own.view.offsets = {own.offsets.data(), own.offsets.size(), ScalarType::int64};
  own.view.cell_types = own.types.data();
  own.view.cell_type_count = own.types.size();
  own.view.ghost_cells = nullptr;
  return own;
}

}  // namespace penumbra::insitu
