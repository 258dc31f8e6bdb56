// SPDX-License-Identifier: BSD-3-Clause
// bench/occlusion/exodus_mesh.cpp -- hexahedra and a nodal field from an Exodus II file
#include "exodus_mesh.h"

#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkExodusIIReader.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>

#include <filesystem>

#include "penumbra/core/error.h"

namespace penumbra::bench {

HexMesh read_exodus_hexes(const std::string& path, const std::string& field) {
  if (!std::filesystem::is_regular_file(path))
    throw Error(ErrorCode::io_error, "read_exodus_hexes: '" + path + "' does not exist");
  vtkNew<vtkExodusIIReader> reader;
  if (!reader->CanReadFile(path.c_str()))
    throw Error(ErrorCode::io_error, "read_exodus_hexes: '" + path + "' is not an Exodus II file");
  reader->SetFileName(path.c_str());
  reader->UpdateInformation();
  reader->SetAllArrayStatus(vtkExodusIIReader::NODAL, 1);
  reader->Update();
  // Element blocks are the first child of the reader's output; the blocks of one file share its
  // node numbering only through the global ids, so a file with several blocks is refused here.
  auto* blocks = vtkMultiBlockDataSet::SafeDownCast(reader->GetOutput()->GetBlock(0));
  if (blocks == nullptr || blocks->GetNumberOfBlocks() != 1)
    throw Error(ErrorCode::invalid_argument, "read_exodus_hexes: '" + path + "' must hold exactly one element block");
  auto* grid = vtkUnstructuredGrid::SafeDownCast(blocks->GetBlock(0));
  if (grid == nullptr) throw Error(ErrorCode::io_error, "read_exodus_hexes: '" + path + "' has no unstructured block");
  vtkDataArray* values = grid->GetPointData()->GetArray(field.c_str());
  if (values == nullptr || values->GetNumberOfComponents() != 1)
    throw Error(ErrorCode::invalid_argument, "read_exodus_hexes: '" + path + "' has no scalar nodal field '" + field + "'");
  HexMesh mesh;
  const vtkIdType np = grid->GetNumberOfPoints(), nc = grid->GetNumberOfCells();
  mesh.points.resize(static_cast<std::size_t>(np) * 3);
  mesh.field.resize(static_cast<std::size_t>(np));
  for (vtkIdType i = 0; i < np; ++i) {
    grid->GetPoint(i, &mesh.points[static_cast<std::size_t>(i) * 3]);
    mesh.field[static_cast<std::size_t>(i)] = static_cast<float>(values->GetTuple1(i));
  }
  mesh.hexes.reserve(static_cast<std::size_t>(nc) * 8);
  vtkIdType count = 0;
  const vtkIdType* ids = nullptr;
  for (vtkIdType c = 0; c < nc; ++c) {
    grid->GetCells()->GetCellAtId(c, count, ids);
    if (grid->GetCellType(c) != VTK_HEXAHEDRON || count != 8)
      throw Error(ErrorCode::invalid_argument, "read_exodus_hexes: '" + path + "' cell " + std::to_string(c) +
                                                   " has VTK type " + std::to_string(grid->GetCellType(c)) +
                                                   ", expected 12 (hexahedron)");
    mesh.hexes.insert(mesh.hexes.end(), ids, ids + 8);
  }
  return mesh;
}

}  // namespace penumbra::bench
