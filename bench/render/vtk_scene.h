// SPDX-License-Identifier: BSD-3-Clause
// bench/render/vtk_scene.h -- a benchmark scene as a vtkUnstructuredGrid for VTK's mappers
#pragma once
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include "scene.h"

namespace penumbra::bench {

/// The scene's tets with its per-point scalar (named "s") as the active point scalars.
vtkSmartPointer<vtkUnstructuredGrid> make_grid(const Scene& scene);

}  // namespace penumbra::bench
