// SPDX-License-Identifier: BSD-3-Clause
// tests/mpi/mpi_partition.h -- the test mesh cut the ways solvers cut theirs, its field, its descriptor
#pragma once
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#ifdef PNB_HAVE_METIS
#include <metis.h>
#endif

#include "fixtures/meshes.h"
#include "penumbra/penumbra.h"

namespace penumbra::mpi_test {

using fixtures::OwnedMesh;

inline double field_at(double x, double y, double z, int step) { return std::sin(5 * x + step) + std::cos(3 * y) + z; }

// The rank that owns each cell of `whole` (a tet mesh over the unit cube).
inline std::vector<int> owners(const OwnedMesh& whole, const std::string& kind, int ranks) {
  const std::size_t cells = whole.cell_count();
  std::vector<int> owner(cells, 0);
  if (kind == "metis") {
#ifdef PNB_HAVE_METIS
    if (ranks == 1) return owner;
    std::vector<idx_t> eptr(whole.offsets.begin(), whole.offsets.end()), eind(whole.connectivity.begin(), whole.connectivity.end());
    idx_t ne = static_cast<idx_t>(cells), nn = static_cast<idx_t>(whole.point_count()), common = 3, parts = ranks, cut = 0;
    std::vector<idx_t> epart(cells), npart(whole.point_count());
    idx_t options[METIS_NOPTIONS];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_SEED] = 7;  // the same parts on every rank and every run
    if (METIS_PartMeshDual(&ne, &nn, eptr.data(), eind.data(), nullptr, nullptr, &common, &parts, nullptr, options, &cut,
                           epart.data(), npart.data()) != METIS_OK)
      std::abort();
    for (std::size_t c = 0; c < cells; ++c) owner[c] = static_cast<int>(epart[c]);
    return owner;
#else
    std::fprintf(stderr, "built without METIS\n");
    std::abort();
#endif
  }
  for (std::size_t c = 0; c < cells; ++c) {
    const auto begin = static_cast<std::size_t>(whole.offsets[c]), end = static_cast<std::size_t>(whole.offsets[c + 1]);
    double cx = 0;
    for (std::size_t k = begin; k < end; ++k) cx += whole.xyz[3 * static_cast<std::size_t>(whole.connectivity[k])];
    cx /= static_cast<double>(end - begin);
    owner[c] = kind == "slabs" ? std::min(ranks - 1, static_cast<int>(cx * ranks)) : static_cast<int>(c % static_cast<std::size_t>(ranks));
  }
  return owner;
}

// A rank's part of the mesh: its cells (and with ghosts, the cells of other ranks that share a
// point with them, marked ghost), the points they use (renumbered in first-use order), and each
// cell's index in the whole mesh.
struct Part {
  OwnedMesh mesh;
  std::vector<std::uint8_t> ghosts;
  std::vector<std::size_t> whole_cell;
};

inline Part partition(const OwnedMesh& whole, const std::string& kind, int rank, int ranks, bool with_ghosts) {
  Part part;
  std::map<std::int64_t, std::int64_t> local;
  const std::vector<int> owner = owners(whole, kind, ranks);
  std::vector<char> touches(whole.point_count(), 0);  // points of this rank's own cells
  for (std::size_t c = 0; c < whole.cell_count(); ++c)
    if (owner[c] == rank)
      for (auto k = whole.offsets[c]; k < whole.offsets[c + 1]; ++k) touches[static_cast<std::size_t>(whole.connectivity[static_cast<std::size_t>(k)])] = 1;
  for (std::size_t c = 0; c < whole.cell_count(); ++c) {
    const auto begin = static_cast<std::size_t>(whole.offsets[c]), end = static_cast<std::size_t>(whole.offsets[c + 1]);
    bool near = false;
    for (std::size_t k = begin; k < end; ++k) near = near || touches[static_cast<std::size_t>(whole.connectivity[k])];
    const bool ghost = owner[c] != rank;
    if (ghost && !(with_ghosts && near)) continue;
    part.ghosts.push_back(ghost ? 1 : 0);
    part.whole_cell.push_back(c);
    for (std::size_t k = begin; k < end; ++k) {
      const std::int64_t g = whole.connectivity[k];
      auto [it, added] = local.try_emplace(g, static_cast<std::int64_t>(part.mesh.point_count()));
      if (added) part.mesh.add_point(whole.xyz[3 * g], whole.xyz[3 * g + 1], whole.xyz[3 * g + 2]);
      part.mesh.connectivity.push_back(it->second);
    }
    part.mesh.offsets.push_back(static_cast<std::int64_t>(part.mesh.connectivity.size()));
    part.mesh.types.push_back(whole.types[c]);
  }
  return part;
}

// This rank's part: its share of `whole`, or none on `empty_rank` (-1: no rank is empty), whose
// share the other ranks split among themselves.
inline Part part_of(const OwnedMesh& whole, const std::string& kind, int rank, int ranks, bool with_ghosts, int empty_rank) {
  if (empty_rank < 0) return partition(whole, kind, rank, ranks, with_ghosts);
  if (rank == empty_rank) return Part{};
  return partition(whole, kind, rank < empty_rank ? rank : rank - 1, ranks - 1, with_ghosts);
}

// `mesh` as the C API takes it (topology_version 1).
inline pnb_mesh_desc mesh_desc(const OwnedMesh& mesh) {
  pnb_mesh_desc m = PNB_MESH_DESC_INIT;
  m.points = mesh.xyz.data();
  m.point_count = static_cast<int64_t>(mesh.point_count());
  m.connectivity = mesh.connectivity.data();
  m.connectivity_count = static_cast<int64_t>(mesh.connectivity.size());
  m.offsets = mesh.offsets.data();
  m.cell_types = mesh.types.data();
  m.cell_types_count = static_cast<int64_t>(mesh.types.size());
  m.topology_version = 1;
  return m;
}

}  // namespace penumbra::mpi_test
