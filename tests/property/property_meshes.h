// SPDX-License-Identifier: BSD-3-Clause
// tests/property/property_meshes.h -- the meshes the property tests draw from: procedural blocks of
// every cell kind (jittered, with holes, of random proportions) and, in builds that read VTK and
// Exodus files, the real meshes of tests/data
#pragma once
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "fixtures/meshes.h"

namespace penumbra::test {

/// The real meshes of tests/data this build can read (none without the VTK adaptor).
std::vector<std::string> real_mesh_files();

/// Reads the first step of `file` (in tests/data) as an owned mesh.
fixtures::OwnedMesh read_real_mesh(const std::string& file);

/// A mesh drawn by `rng`, with a name that says what it is.
std::pair<std::string, fixtures::OwnedMesh> random_mesh(std::mt19937_64& rng);

}  // namespace penumbra::test
