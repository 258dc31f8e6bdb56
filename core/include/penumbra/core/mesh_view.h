// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/mesh_view.h
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>

#include "penumbra/core/vec3.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra {

/// Element type of caller arrays.
enum class ScalarType : std::uint8_t { float32, float64, int32, int64 };

/// Bytes per element of `t`.
constexpr std::size_t scalar_size(ScalarType t) {
  return (t == ScalarType::float32 || t == ScalarType::int32) ? 4 : 8;
}

/// VTK cell type ids of the volume cells Penumbra renders.
enum class CellType : std::uint8_t { tetra = 10, hexahedron = 12, wedge = 13, pyramid = 14 };

/// Number of points of a cell type, or 0 for an unsupported id.
constexpr int cell_point_count(std::uint8_t vtk_type) {
  switch (vtk_type) {
    case 10: return 4;
    case 12: return 8;
    case 13: return 6;
    case 14: return 5;
    default: return 0;
  }
}

/// Non-owning view of `count` items of caller memory, `stride_bytes` apart. Owns nothing;
/// valid only as long as the caller's array.
struct StridedSpan {
  const std::byte* data = nullptr;
  std::size_t count = 0;
  std::ptrdiff_t stride_bytes = 0;
  const std::byte* at(std::size_t i) const { return data + static_cast<std::ptrdiff_t>(i) * stride_bytes; }
};

/// Non-owning view of a contiguous integer array (int32 or int64).
struct IndexArray {
  const void* data = nullptr;
  std::size_t count = 0;
  ScalarType type = ScalarType::int64;
  std::int64_t operator[](std::size_t i) const {
    return type == ScalarType::int32 ? static_cast<const std::int32_t*>(data)[i]
                                     : static_cast<const std::int64_t*>(data)[i];
  }
};

/// A solver's unstructured volume mesh as views of its own arrays, in VTK ordering.
/// Cheap to copy, owns nothing, valid only during the call that receives it.
///
/// - `points`: one item per point; each item holds x, y, z contiguous in `point_type`
///   (float32 or float64); `stride_bytes` is the distance between points (12/24 when packed).
///   `points.count` is the number of points in either layout.
/// - `axes`: the coordinates as three arrays instead (x, y, z, each `stride_bytes` apart), used
///   when `points.data` is null.
/// - `connectivity`: point ids of all cells, cell after cell.
/// - `offsets`: cell c uses connectivity[offsets[c] .. offsets[c+1]); count = cells + 1.
///   May be empty when `cell_types` has a single entry (all cells of one type).
/// - `cell_types`: VTK type id per cell, or one entry meaning every cell has that type.
/// - `topology_version`: bump it when connectivity or points change; republishing the same
///   version lets Penumbra skip all mesh preparation.
struct MeshView {
  StridedSpan points;
  std::array<StridedSpan, 3> axes;
  ScalarType point_type = ScalarType::float64;
  IndexArray connectivity;
  IndexArray offsets;
  const std::uint8_t* cell_types = nullptr;
  std::size_t cell_type_count = 0;
  std::uint64_t topology_version = 0;
  /// VTK's vtkGhostType per cell, or null: a cell with the duplicate-cell bit (kDuplicateCell) is
  /// another rank's copy, kept for what its points average (cell fields) but never rendered, lit
  /// or stored as this rank's.
  const std::uint8_t* ghost_cells = nullptr;
  static constexpr std::uint8_t kDuplicateCell = 1;  ///< vtkDataSetAttributes::DUPLICATECELL
  bool ghost(std::size_t c) const { return ghost_cells != nullptr && (ghost_cells[c] & kDuplicateCell) != 0; }

  std::size_t point_count() const { return points.count; }
  /// Number of cells implied by offsets or, for a uniform mesh, connectivity / points-per-cell.
  std::size_t cell_count() const;
  std::uint8_t cell_type(std::size_t c) const { return cell_type_count == 1 ? cell_types[0] : cell_types[c]; }
  std::int64_t cell_begin(std::size_t c) const;
  Vec3d point(std::size_t i) const;
};

}  // namespace penumbra

PNB_PUBLIC_END
