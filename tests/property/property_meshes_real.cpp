// SPDX-License-Identifier: BSD-3-Clause
// tests/property/property_meshes_real.cpp -- the real meshes of tests/data, read through the VTK
// adaptor and penumbra-replay's readers (builds with the adaptor)
#include <string>
#include <vector>

#include <vtkUnstructuredGrid.h>

#include "input_series.h"
#include "penumbra/vtk/unstructured_grid_adaptor.h"
#include "property_meshes.h"

namespace penumbra::test {

std::vector<std::string> real_mesh_files() { return {"mug.e", "disk_out_ref.ex2", "can.vtu", "mesh_fs8.exo", "post.vtk"}; }

fixtures::OwnedMesh read_real_mesh(const std::string& file) {
  auto series = replay::InputSeries::open(std::string(PNB_TEST_DATA_DIR) + "/" + file);
  const replay::Step step = series->load(0);
  const penumbra::vtk::UnstructuredGridAdaptor adaptor(step.grid);
  const MeshView v = adaptor.mesh_view();
  fixtures::OwnedMesh m;
  m.xyz.clear();
  for (std::size_t i = 0; i < v.point_count(); ++i) m.add_point(v.point(i).x, v.point(i).y, v.point(i).z);
  m.offsets = {0};
  for (std::size_t c = 0; c < v.cell_count(); ++c) {
    const std::int64_t b = v.cell_begin(c);
    const int n = cell_point_count(v.cell_type(c));
    for (int k = 0; k < n; ++k) m.connectivity.push_back(v.connectivity[static_cast<std::size_t>(b + k)]);
    m.offsets.push_back(static_cast<std::int64_t>(m.connectivity.size()));
    m.types.push_back(v.cell_type(c));
  }
  return m;
}

}  // namespace penumbra::test
