// SPDX-License-Identifier: BSD-3-Clause
// adaptors/vtk/include/penumbra/vtk/unstructured_grid_adaptor.h
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "penumbra/core/mesh_view.h"
#include "penumbra/penumbra.h"

class vtkUnstructuredGrid;

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::vtk {

/// What the adaptor had to copy and what it dropped; everything not listed is a view of the
/// grid's own arrays.
struct AdaptorReport {
  std::size_t input_cells = 0;          ///< cells in the vtkUnstructuredGrid
  std::size_t volume_cells = 0;         ///< cells published (tet, hex, wedge, pyramid)
  std::size_t linearized_cells = 0;     ///< voxels and quadratic cells reduced to their corners
  std::size_t dropped_surface_cells = 0;      ///< 0-, 1- and 2-D cells (vertices, lines, faces)
  std::size_t dropped_unsupported_cells = 0;  ///< 3-D cells Penumbra cannot render (polyhedra...)
  bool points_copied = false;           ///< points were not packed float32/float64 xyz
  bool cells_copied = false;            ///< connectivity/offsets/types were rebuilt
  std::vector<std::string> copied_fields;   ///< fields converted or filtered into owned storage
  std::vector<std::string> skipped_arrays;  ///< arrays without a name or of a non-numeric type
  std::vector<std::string> unconverted_fields;  ///< needed a copy but the caller's filter declined it

  /// One line for logs, e.g. "8750 cells: zero-copy mesh, 1 field copied (material: int32)".
  std::string summary() const;
};

/// Views of a vtkUnstructuredGrid as the C API's pnb_mesh_desc and pnb_field_desc.
///
/// Zero-copy where the layout allows: a VTK 9 vtkCellArray keeps offsets and connectivity as
/// contiguous int32 or int64 arrays, points as packed float/double xyz and cell types as one
/// uint8 per cell, which are exactly the C API's layouts, so the descriptors point straight at
/// the grid's memory. The adaptor copies into storage it owns only when it must:
/// - the grid mixes volume cells with cells Penumbra does not render (faces, lines, polyhedra):
///   those are filtered out, so cells, cell types and every cell field are rebuilt;
/// - voxels (VTK 11) are reordered into hexahedra and quadratic volume cells (VTK 24-27, 29, 31-33)
///   are reduced to their linear corners;
/// - points or field values are not packed float32/float64 (e.g. int arrays, SOA layouts):
///   they are converted to float64.
/// report() says which of these happened.
///
/// The adaptor holds a reference to the grid, so the descriptors stay valid for the adaptor's
/// lifetime as long as nobody modifies the grid's arrays. Not thread-safe. The descriptors are
/// meant for pnb_publish_mesh/pnb_publish_field with PNB_BORROW.
///
/// Spell it penumbra::vtk::UnstructuredGridAdaptor: after `using namespace penumbra;` a bare
/// `vtk::` is ambiguous with VTK's own namespace `vtk`.
class UnstructuredGridAdaptor {
public:
  /// Builds the views. Throws penumbra::Error(invalid_argument) when `grid` is null, has no
  /// points, or has no volume cell (e.g. a surface mesh), naming what it found instead.
  explicit UnstructuredGridAdaptor(vtkUnstructuredGrid* grid, std::uint64_t topology_version = 1);

  /// Decides, by name, whether a field that cannot be viewed (it needs a conversion or a filter)
  /// is copied. Fields that can be viewed are always exposed: they cost nothing.
  using CopyFilter = std::function<bool(std::string_view name)>;
  /// As above; fields for which `copy_filter` returns false are left out of fields() (and listed
  /// in report().unconverted_fields) instead of being copied.
  UnstructuredGridAdaptor(vtkUnstructuredGrid* grid, std::uint64_t topology_version, CopyFilter copy_filter);
  ~UnstructuredGridAdaptor();
  UnstructuredGridAdaptor(UnstructuredGridAdaptor&&) noexcept;
  UnstructuredGridAdaptor& operator=(UnstructuredGridAdaptor&&) noexcept;
  UnstructuredGridAdaptor(const UnstructuredGridAdaptor&) = delete;
  UnstructuredGridAdaptor& operator=(const UnstructuredGridAdaptor&) = delete;

  /// The mesh, ready for pnb_publish_mesh. Pointers stay valid for the adaptor's lifetime.
  const pnb_mesh_desc& mesh() const;
  /// The same mesh as a core view (for C++ callers and validation).
  MeshView mesh_view() const;
  /// Every named numeric point and cell array of the grid, point fields first, in the grid's
  /// order; cell fields match the published (possibly filtered) cells.
  const std::vector<pnb_field_desc>& fields() const;
  /// The field called `name` with that association, or nullptr.
  const pnb_field_desc* find_field(std::string_view name, pnb_association association) const;
  /// What was copied or dropped.
  const AdaptorReport& report() const;
  /// True when the mesh descriptor points into the grid's own arrays (nothing copied).
  bool mesh_is_zero_copy() const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

/// Name of a pnb_type for messages ("float32", ...).
const char* type_name(pnb_type type);

}  // namespace penumbra::vtk

PNB_PUBLIC_END
