// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/stored_mesh.h -- a published mesh written to and read from a file of its own
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/core/mesh_view.h"

namespace penumbra::insitu {

/// An owned copy of a mesh: float64 points, int64 connectivity and offsets, a type per cell.
struct StoredMesh {
  std::vector<double> xyz;
  std::vector<std::int64_t> connectivity, offsets;
  std::vector<std::uint8_t> types;
  MeshView view() const;
};

/// Copies `mesh` into owned arrays (points converted to float64, ids to int64).
StoredMesh copy_mesh(const MeshView& mesh);

/// Writes `mesh` to `path` atomically: magic "PNBMESH1", counts, arrays, then a 64-bit FNV-1a
/// checksum of everything before it. Throws Error(io_error) naming the path on failure.
void write_stored_mesh(const std::string& path, const StoredMesh& mesh);

/// Reads a file written by write_stored_mesh; throws Error(io_error) naming the path and what is
/// wrong (missing, not a mesh file, truncated, checksum mismatch, inconsistent counts).
StoredMesh read_stored_mesh(const std::string& path);

/// Parses the `size` bytes of such a file at `bytes`; errors as above, naming `path`.
StoredMesh parse_stored_mesh(const unsigned char* bytes, std::size_t size, const std::string& path);

}  // namespace penumbra::insitu
