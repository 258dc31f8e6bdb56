// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/vtk/vtk_test_util.h -- small VTK grids and temp directories for the adaptor tests
#pragma once
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include <filesystem>
#include <string>

#include "fixtures/meshes.h"

namespace penumbra::test {

/// The fixture mesh as a vtkUnstructuredGrid with 64- or 32-bit cell storage and points of
/// VTK type `point_type` (VTK_DOUBLE, VTK_FLOAT, ...).
vtkSmartPointer<vtkUnstructuredGrid> to_vtk(const fixtures::OwnedMesh& mesh, bool storage64 = true,
                                            int point_type = VTK_DOUBLE);

/// A fresh empty directory under the system temp dir, removed by the destructor.
class TempDir {
public:
  explicit TempDir(const std::string& tag);
  ~TempDir();
  const std::filesystem::path& path() const { return m_path; }

private:
  std::filesystem::path m_path;
};

/// The real meshes bundled with the tests (tests/data/README.md).
inline std::filesystem::path data_dir() { return PNB_TEST_DATA_DIR; }

}  // namespace penumbra::test
