// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/vtk/vtk_test_util.cpp
#include "vtk_test_util.h"

#include <vtkCellArray.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkTypeInt32Array.h>
#include <vtkTypeInt64Array.h>
#include <vtkUnsignedCharArray.h>

#include <random>

namespace penumbra::test {

template <class Array>
vtkSmartPointer<vtkCellArray> cells_of(const fixtures::OwnedMesh& mesh) {
  vtkNew<Array> offsets, connectivity;
  for (auto o : mesh.offsets) offsets->InsertNextValue(static_cast<typename Array::ValueType>(o));
  for (auto c : mesh.connectivity) connectivity->InsertNextValue(static_cast<typename Array::ValueType>(c));
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  cells->SetData(offsets, connectivity);
  return cells;
}

vtkSmartPointer<vtkUnstructuredGrid> to_vtk(const fixtures::OwnedMesh& mesh, bool storage64, int point_type) {
  vtkNew<vtkPoints> points;
  points->SetDataType(point_type);
  for (std::size_t i = 0; i < mesh.point_count(); ++i)
    points->InsertNextPoint(mesh.xyz[3 * i], mesh.xyz[3 * i + 1], mesh.xyz[3 * i + 2]);
  vtkNew<vtkUnsignedCharArray> types;
  for (auto t : mesh.types) types->InsertNextValue(t);
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points);
  grid->SetCells(types, storage64 ? cells_of<vtkTypeInt64Array>(mesh) : cells_of<vtkTypeInt32Array>(mesh));
  return grid;
}

TempDir::TempDir(const std::string& tag) {
  std::random_device rd;
  m_path = std::filesystem::temp_directory_path() / ("pnb_vtk_" + tag + "_" + std::to_string(rd()));
  std::filesystem::remove_all(m_path);
  std::filesystem::create_directories(m_path);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(m_path, ec);
}

}  // namespace penumbra::test
