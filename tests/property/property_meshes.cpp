// SPDX-License-Identifier: BSD-3-Clause
// tests/property/property_meshes.cpp -- random procedural meshes and the choice among them and the
// real meshes (property_meshes_real.cpp or property_meshes_none.cpp says which these are)
#include "property_meshes.h"

#include <algorithm>
#include <cstdio>

namespace penumbra::test {
namespace {

/// Moves the block's interior points by up to a tenth of a cell in each axis: the cells stay
/// positively oriented and conforming, but no face is axis-aligned any more.
void jitter(fixtures::OwnedMesh& m, std::mt19937_64& rng, const Vec3d& lo, const Vec3d& hi, const Vec3d& cell) {
  std::uniform_real_distribution<double> d(-0.1, 0.1);
  for (std::size_t i = 0; i < m.point_count(); ++i)
    for (int a = 0; a < 3; ++a) {
      double& x = m.xyz[3 * i + static_cast<std::size_t>(a)];
      const double eps = 1e-9 * (hi[a] - lo[a]);
      if (x > lo[a] + eps && x < hi[a] - eps) x += d(rng) * cell[a];
    }
}

}  // namespace

std::pair<std::string, fixtures::OwnedMesh> random_mesh(std::mt19937_64& rng) {
  const std::vector<std::string> files = real_mesh_files();
  std::uniform_int_distribution<int> pick(0, 4 + static_cast<int>(files.size()));
  const int kind = pick(rng);
  if (kind > 4) {
    const std::string& f = files[static_cast<std::size_t>(kind - 5)];
    return {f, read_real_mesh(f)};
  }
  if (kind == 4) {
    const int n = std::uniform_int_distribution<int>(5, 9)(rng);
    return {"tet block with a hole, n = " + std::to_string(n), fixtures::tet_block_with_hole(n)};
  }
  std::uniform_real_distribution<double> side(0.5, 2.0);
  std::uniform_int_distribution<int> cells(2, 6);
  const int nx = cells(rng), ny = cells(rng), nz = cells(rng);
  const Vec3d lo{0, 0, 0}, hi{side(rng), side(rng), side(rng)};
  static const fixtures::BlockCells kinds[] = {fixtures::BlockCells::tets, fixtures::BlockCells::hexes,
                                               fixtures::BlockCells::wedges, fixtures::BlockCells::pyramids};
  static const char* names[] = {"tets", "hexes", "wedges", "pyramids"};
  // A few cubes left out now and then: inner holes and a non-convex outline.
  std::vector<char> keep(static_cast<std::size_t>(nx * ny * nz), 1);
  for (char& k : keep) k = std::uniform_real_distribution<double>(0, 1)(rng) < 0.15 ? 0 : 1;
  keep[0] = 1;
  auto m = fixtures::block(kinds[kind], nx, ny, nz, lo, hi,
                           [&](int i, int j, int k) { return keep[static_cast<std::size_t>(i + nx * (j + ny * k))] != 0; });
  jitter(m, rng, lo, hi, Vec3d{hi.x / nx, hi.y / ny, hi.z / nz});
  char name[96];
  std::snprintf(name, sizeof name, "jittered block of %s, %dx%dx%d", names[kind], nx, ny, nz);
  return {name, std::move(m)};
}

}  // namespace penumbra::test
