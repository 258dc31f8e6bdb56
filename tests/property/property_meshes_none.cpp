// SPDX-License-Identifier: BSD-3-Clause
// tests/property/property_meshes_none.cpp -- builds without the VTK adaptor read no real meshes
#include "penumbra/core/error.h"
#include "property_meshes.h"

namespace penumbra::test {

std::vector<std::string> real_mesh_files() { return {}; }

fixtures::OwnedMesh read_real_mesh(const std::string& file) {
  throw Error(ErrorCode::invalid_operation, "read_real_mesh(" + file + "): this build has no VTK adaptor");
}

}  // namespace penumbra::test
