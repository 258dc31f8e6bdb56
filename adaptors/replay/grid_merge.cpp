// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/grid_merge.cpp -- multi-block reader output merged into one grid
#include "grid_merge.h"

#include <vtkAppendFilter.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCompositeDataIterator.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>

#include <string>
#include <unordered_map>
#include <vector>

#include "penumbra/core/error.h"

namespace penumbra::replay {
namespace {

std::vector<vtkUnstructuredGrid*> unstructured_leaves(vtkCompositeDataSet* composite) {
  std::vector<vtkUnstructuredGrid*> leaves;
  vtkSmartPointer<vtkCompositeDataIterator> it;
  it.TakeReference(composite->NewIterator());
  it->SkipEmptyNodesOn();
  for (it->InitTraversal(); !it->IsDoneWithTraversal(); it->GoToNextItem()) {
    auto* grid = vtkUnstructuredGrid::SafeDownCast(it->GetCurrentDataObject());
    if (grid && grid->GetNumberOfCells() > 0) leaves.push_back(grid);
  }
  return leaves;
}

/// The node-id array every leaf has, or nullptr.
const char* shared_id_array(const std::vector<vtkUnstructuredGrid*>& leaves) {
  for (const char* name : {"GlobalNodeId", "PedigreeNodeId"}) {
    bool all = true;
    for (auto* g : leaves) all = all && g->GetPointData()->GetArray(name) != nullptr;
    if (all) return name;
  }
  return nullptr;
}

vtkSmartPointer<vtkUnstructuredGrid> merge_by_node_id(const std::vector<vtkUnstructuredGrid*>& leaves,
                                                      const char* id_name) {
  const int n = static_cast<int>(leaves.size());
  vtkDataSetAttributes::FieldList point_fields(n), cell_fields(n);
  vtkIdType total_points = 0, total_cells = 0;
  for (int b = 0; b < n; ++b) {
    if (b == 0) {
      point_fields.InitializeFieldList(leaves[b]->GetPointData());
      cell_fields.InitializeFieldList(leaves[b]->GetCellData());
    } else {
      point_fields.IntersectFieldList(leaves[b]->GetPointData());
      cell_fields.IntersectFieldList(leaves[b]->GetCellData());
    }
    total_points += leaves[b]->GetNumberOfPoints();
    total_cells += leaves[b]->GetNumberOfCells();
  }

  auto out = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkPoints> points;
  points->SetDataType(leaves[0]->GetPoints()->GetDataType());
  points->Allocate(total_points);
  // Global ids are not copied by default; the merged grid keeps them (they identify nodes).
  out->GetPointData()->CopyAllOn();
  out->GetCellData()->CopyAllOn();
  out->GetPointData()->CopyAllocate(point_fields, total_points);
  out->GetCellData()->CopyAllocate(cell_fields, total_cells);
  out->AllocateExact(total_cells, total_cells * 8);

  std::unordered_map<vtkIdType, vtkIdType> merged;  // node id -> output point
  merged.reserve(static_cast<std::size_t>(total_points));
  vtkNew<vtkIdList> cell_points;
  for (int b = 0; b < n; ++b) {
    vtkUnstructuredGrid* g = leaves[b];
    vtkDataArray* ids = g->GetPointData()->GetArray(id_name);
    std::vector<vtkIdType> local(static_cast<std::size_t>(g->GetNumberOfPoints()));
    for (vtkIdType p = 0; p < g->GetNumberOfPoints(); ++p) {
      const auto key = static_cast<vtkIdType>(ids->GetComponent(p, 0));
      auto [it, fresh] = merged.emplace(key, points->GetNumberOfPoints());
      if (fresh) {
        points->InsertNextPoint(g->GetPoint(p));
        out->GetPointData()->CopyData(point_fields, g->GetPointData(), b, p, it->second);
      }
      local[static_cast<std::size_t>(p)] = it->second;
    }
    for (vtkIdType c = 0; c < g->GetNumberOfCells(); ++c) {
      g->GetCellPoints(c, cell_points);
      for (vtkIdType k = 0; k < cell_points->GetNumberOfIds(); ++k)
        cell_points->SetId(k, local[static_cast<std::size_t>(cell_points->GetId(k))]);
      const vtkIdType to = out->InsertNextCell(g->GetCellType(c), cell_points);
      out->GetCellData()->CopyData(cell_fields, g->GetCellData(), b, c, to);
    }
  }
  out->SetPoints(points);
  out->Squeeze();
  return out;
}

vtkSmartPointer<vtkUnstructuredGrid> merge_geometrically(const std::vector<vtkUnstructuredGrid*>& leaves) {
  vtkNew<vtkAppendFilter> append;
  append->MergePointsOn();
  append->SetTolerance(0.0);
  for (auto* g : leaves) append->AddInputData(g);
  append->Update();
  vtkSmartPointer<vtkUnstructuredGrid> out = append->GetOutput();
  return out;
}

}  // namespace

vtkSmartPointer<vtkUnstructuredGrid> merge_to_grid(vtkDataObject* data, const char* what) {
  if (auto* grid = vtkUnstructuredGrid::SafeDownCast(data)) return grid;
  auto* composite = vtkCompositeDataSet::SafeDownCast(data);
  const std::string source = what ? what : "input";
  if (!composite)
    throw Error(ErrorCode::invalid_argument,
                source + ": holds a " + (data ? data->GetClassName() : std::string("null object")) +
                    ", expected an unstructured grid");
  const auto leaves = unstructured_leaves(composite);
  if (leaves.empty())
    throw Error(ErrorCode::invalid_argument, source + ": has no unstructured block with cells");
  if (leaves.size() == 1) return leaves[0];  // no copy: the adaptor views the block itself

  const char* id_name = shared_id_array(leaves);
  auto out = id_name ? merge_by_node_id(leaves, id_name) : merge_geometrically(leaves);
  vtkFieldData* fd = composite->GetFieldData();
  out->GetFieldData()->ShallowCopy(fd && fd->GetNumberOfArrays() > 0 ? fd : leaves[0]->GetFieldData());
  return out;
}

}  // namespace penumbra::replay
