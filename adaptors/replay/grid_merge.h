// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/grid_merge.h -- one vtkUnstructuredGrid out of a reader's multi-block output
#pragma once
#include <vtkSmartPointer.h>

class vtkDataObject;
class vtkUnstructuredGrid;

namespace penumbra::replay {

/// Turns a reader's output into one grid. A vtkUnstructuredGrid is returned as is (no copy);
/// a composite data set with a single non-empty unstructured leaf returns that leaf. Several
/// leaves are merged:
/// - when every leaf carries a "GlobalNodeId" (or else "PedigreeNodeId") point array, points
///   with the same id become one point (Exodus blocks share nodes; without this the shared
///   faces would look like internal boundaries);
/// - otherwise coincident points are merged geometrically (vtkAppendFilter, MergePoints).
/// Point and cell arrays present in every leaf are kept; field data (TIME, CYCLE...) comes
/// from the composite or else its first leaf. Throws penumbra::Error(invalid_argument) when the
/// object holds no unstructured grid with cells.
vtkSmartPointer<vtkUnstructuredGrid> merge_to_grid(vtkDataObject* data, const char* what);

}  // namespace penumbra::replay
