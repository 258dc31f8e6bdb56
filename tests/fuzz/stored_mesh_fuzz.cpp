// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/stored_mesh_fuzz.cpp -- the store's mesh file (.pnbm) reader (parse_stored_mesh,
// which read_stored_mesh calls on the file's bytes), then the mesh it gives through
// validate_mesh, as penumbra-replay publishes it. Each input is read as it is and again with its
// FNV-1a checksum made right, so that mutations get past the checksum to the counts and offsets.
#include <cstdint>
#include <vector>

#include "fuzz_util.h"
#include "penumbra/core/error.h"
#include "penumbra/core/mesh_validation.h"
#include "stored_mesh.h"

namespace {

void read(const std::vector<std::uint8_t>& bytes) {
  using penumbra::Error;
  penumbra::insitu::StoredMesh mesh;
  try {
    mesh = penumbra::insitu::parse_stored_mesh(bytes.data(), bytes.size(), "mesh.pnbm");
  } catch (const Error& e) {
    penumbra::fuzz::expect_code(e, penumbra::ErrorCode::io_error, "parse_stored_mesh");
    return;
  }
  if (mesh.xyz.size() % 3 != 0 || mesh.offsets.size() != mesh.types.size() + 1)
    penumbra::fuzz::fail("parse_stored_mesh returned inconsistent arrays");
  try {
    penumbra::validate_mesh(mesh.view(), "stored mesh");
  } catch (const Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> bytes(data, data + size);
  read(bytes);
  // The checksum is the last 8 bytes: FNV-1a (64 bit) of all before them.
  if (size >= 16) {
    std::uint64_t h = 1469598103934665603ull;
    for (std::size_t i = 0; i + 8 < size; ++i) h = (h ^ bytes[i]) * 1099511628211ull;
    if (penumbra::fuzz::load<std::uint64_t>(bytes, size - 8) != h) {
      penumbra::fuzz::store(bytes, size - 8, h);
      read(bytes);
    }
  }
  return 0;
}
