// SPDX-License-Identifier: BSD-3-Clause
// bench/render/vtk_scene.cpp -- a benchmark scene as a vtkUnstructuredGrid
#include "vtk_scene.h"

#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>

namespace penumbra::bench {

vtkSmartPointer<vtkUnstructuredGrid> make_grid(const Scene& scene) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(scene.point_count()));
  for (std::size_t i = 0; i < scene.point_count(); ++i)
    points->SetPoint(static_cast<vtkIdType>(i), &scene.points[i * 3]);
  vtkNew<vtkIdTypeArray> offsets, connectivity;
  offsets->SetNumberOfValues(static_cast<vtkIdType>(scene.tet_count() + 1));
  for (std::size_t c = 0; c <= scene.tet_count(); ++c) offsets->SetValue(static_cast<vtkIdType>(c), 4 * static_cast<vtkIdType>(c));
  connectivity->SetNumberOfValues(static_cast<vtkIdType>(scene.tets.size()));
  for (std::size_t i = 0; i < scene.tets.size(); ++i) connectivity->SetValue(static_cast<vtkIdType>(i), scene.tets[i]);
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  vtkNew<vtkFloatArray> scalars;
  scalars->SetName("s");
  scalars->SetNumberOfValues(static_cast<vtkIdType>(scene.scalars.size()));
  for (std::size_t i = 0; i < scene.scalars.size(); ++i) scalars->SetValue(static_cast<vtkIdType>(i), scene.scalars[i]);
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points);
  grid->SetCells(VTK_TETRA, cells);
  grid->GetPointData()->SetScalars(scalars);
  return grid;
}

}  // namespace penumbra::bench
