// SPDX-License-Identifier: BSD-3-Clause
// bench/occlusion/exodus_mesh.h -- one element block of hexahedra and a nodal field from an
// Exodus II file (for the occlusion scene on tests/data/disk_out_ref.ex2)
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace penumbra::bench {

struct HexMesh {
  std::vector<double> points;        ///< x, y, z per point
  std::vector<std::int64_t> hexes;   ///< 8 point ids per hexahedron, VTK ordering
  std::vector<float> field;          ///< the requested nodal field, one value per point
};

/// Reads every element block of `path` (all hexahedra, merged on the reader's point numbering of
/// the first block) and nodal field `field` at the first time step. Throws penumbra::Error naming
/// the file for an unreadable file, a missing field or a cell that is not a hexahedron.
HexMesh read_exodus_hexes(const std::string& path, const std::string& field);

}  // namespace penumbra::bench
