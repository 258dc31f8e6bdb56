// SPDX-License-Identifier: BSD-3-Clause
// examples/advection_diffusion_mpi/main.cpp -- the advection-diffusion mini-app over MPI ranks.
//
// The domain of examples/advection_diffusion (an L-shaped slab with a square through-hole, tets
// six per cube) is cut into one part per rank by METIS over the cubes' face graph (slabs where
// METIS is not installed): non-convex, interleaved parts, as a solver's partitioner makes them.
// Each rank advances the temperature at the grid nodes it owns (a node belongs to the lowest rank
// whose cubes touch it); the new values are summed over the ranks (MPI_Allreduce), which here
// stands in for a halo exchange. Each rank then publishes only its own cubes' tets and their
// points, through pnb_create_mpi: Penumbra composites the ranks' ray runs, and rank 0 writes one
// Cinema database, the whole domain's pictures.
// Usage: mpirun -np 4 penumbra-example-advection-mpi [OUTPUT_DIR]   (default ./penumbra-example-mpi-db)
#include <mpi.h>

#ifdef PNB_HAVE_METIS
#include <metis.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "penumbra/penumbra_mpi.h"

namespace {

constexpr int nx = 24, ny = 24, nz = 6;
constexpr double size_xy = 2.0, size_z = 0.5;
constexpr double h = size_xy / nx;
constexpr double hole_lo = 0.35, hole_hi = 0.65;
constexpr int kCycles = 176, kEvery = 16;

bool keep_cube(int i, int j) {
  const double x = (i + 0.5) * h, y = (j + 0.5) * h;
  if (x > 1 && y > 1) return false;
  return !(x > hole_lo && x < hole_hi && y > hole_lo && y < hole_hi);
}
int node(int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; }
constexpr int kNodes = (nx + 1) * (ny + 1) * (nz + 1);

struct Cube {
  int i, j, k;
};

std::vector<Cube> domain_cubes() {
  std::vector<Cube> cubes;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        if (keep_cube(i, j)) cubes.push_back({i, j, k});
  return cubes;
}

void corners(const Cube& c, int v[8]) {
  const int i = c.i, j = c.j, k = c.k;
  const int n[8] = {node(i, j, k),     node(i + 1, j, k),     node(i + 1, j + 1, k),     node(i, j + 1, k),
                    node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)};
  std::copy(n, n + 8, v);
}

// The rank of each cube: METIS over the cubes sharing faces, else slabs along x.
std::vector<int> deal_cubes(const std::vector<Cube>& cubes, int ranks) {
  std::vector<int> owner(cubes.size(), 0);
  if (ranks == 1) return owner;
#ifdef PNB_HAVE_METIS
  std::vector<idx_t> eptr{0}, eind;
  for (const Cube& c : cubes) {
    int v[8];
    corners(c, v);
    eind.insert(eind.end(), v, v + 8);
    eptr.push_back(static_cast<idx_t>(eind.size()));
  }
  idx_t ne = static_cast<idx_t>(cubes.size()), nn = kNodes, common = 4, parts = ranks, cut = 0;
  std::vector<idx_t> epart(cubes.size()), npart(kNodes);
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;  // every rank computes the same parts
  if (METIS_PartMeshDual(&ne, &nn, eptr.data(), eind.data(), nullptr, nullptr, &common, &parts, nullptr, options, &cut,
                         epart.data(), npart.data()) == METIS_OK) {
    for (std::size_t c = 0; c < cubes.size(); ++c) owner[c] = static_cast<int>(epart[c]);
    return owner;
  }
#endif
  for (std::size_t c = 0; c < cubes.size(); ++c) owner[c] = std::min(ranks - 1, cubes[c].i * ranks / nx);
  return owner;
}

// This rank's part: its cubes as tets over its own points, and which grid node each point is.
struct Part {
  std::vector<float> xyz;
  std::vector<std::int32_t> tets;
  std::vector<int> nodes;         // grid node of each local point
  std::vector<char> owns;         // per grid node: this rank updates it
  std::vector<char> in_domain;    // per grid node: some cube of the domain touches it
};

Part make_part(const std::vector<Cube>& cubes, const std::vector<int>& owner, int rank) {
  Part p;
  std::vector<int> lowest(kNodes, 1 << 30), local(kNodes, -1);
  p.in_domain.assign(kNodes, 0);
  for (std::size_t c = 0; c < cubes.size(); ++c) {
    int v[8];
    corners(cubes[c], v);
    for (int n : v) {
      lowest[n] = std::min(lowest[n], owner[c]);
      p.in_domain[n] = 1;
    }
  }
  p.owns.assign(kNodes, 0);
  for (int n = 0; n < kNodes; ++n) p.owns[n] = lowest[n] == rank;
  static const int split[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
  for (std::size_t c = 0; c < cubes.size(); ++c) {
    if (owner[c] != rank) continue;
    int v[8];
    corners(cubes[c], v);
    for (int n : v)
      if (local[n] < 0) {
        local[n] = static_cast<int>(p.nodes.size());
        p.nodes.push_back(n);
        const int i = n % (nx + 1), j = (n / (nx + 1)) % (ny + 1), k = n / ((nx + 1) * (ny + 1));
        p.xyz.insert(p.xyz.end(), {float(i * h), float(j * h), float(k * size_z / nz)});
      }
    for (const auto& t : split)
      for (int c4 : t) p.tets.push_back(local[v[c4]]);
  }
  return p;
}

// Explicit upwind advection and central diffusion at the grid nodes (examples/advection_diffusion).
struct Solver {
  std::vector<double> temperature = std::vector<double>(kNodes, 0.0);  // every grid node, on every rank
  double omega = 2.0, kappa = 0.001, cx = 0.5, cy = 0.5;

  explicit Solver(const Part& p) {
    for (int n = 0; n < kNodes; ++n) {
      const int i = n % (nx + 1), j = (n / (nx + 1)) % (ny + 1), k = n / ((nx + 1) * (ny + 1));
      const double dx = i * h - 0.5, dy = j * h - 0.12, dz = k * size_z / nz - 0.25;
      temperature[n] = p.in_domain[n] ? 20.0 + 80.0 * std::exp(-(dx * dx + dy * dy + dz * dz) / (2 * 0.12 * 0.12)) : 0.0;
    }
  }
  double stable_dt() const {
    const double umax = omega * std::hypot(std::max(cx, size_xy - cx), std::max(cy, size_xy - cy));
    return 0.6 * std::min(h / umax, h * h / (6 * kappa));
  }
  // The new values of the nodes this rank owns (0 elsewhere), summed over the ranks.
  void step(double dt, const Part& p) {
    std::vector<double> next(kNodes, 0.0);
    for (int n = 0; n < kNodes; ++n) {
      if (!p.owns[n]) continue;
      const int i = n % (nx + 1), j = (n / (nx + 1)) % (ny + 1), k = n / ((nx + 1) * (ny + 1));
      auto at = [&](int a, int b, int c) {
        if (a < 0 || b < 0 || c < 0 || a > nx || b > ny || c > nz) return temperature[n];
        const int q = node(a, b, c);
        return p.in_domain[q] ? temperature[q] : temperature[n];
      };
      const double u = -omega * (j * h - cy), v = omega * (i * h - cx), t = temperature[n];
      const double ddx = u > 0 ? t - at(i - 1, j, k) : at(i + 1, j, k) - t;
      const double ddy = v > 0 ? t - at(i, j - 1, k) : at(i, j + 1, k) - t;
      const double lap = at(i + 1, j, k) + at(i - 1, j, k) + at(i, j + 1, k) + at(i, j - 1, k) + at(i, j, k + 1) +
                         at(i, j, k - 1) - 6 * t;
      next[n] = t - dt * (u * ddx + v * ddy) / h + dt * kappa * lap / (h * h);
    }
    MPI_Allreduce(next.data(), temperature.data(), kNodes, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  }
};

// The serial example's pictures, lit by Phong shading (the light volume does not run over several
// ranks yet).
std::string config_json(const std::string& out) {
  return R"({
    "output": {"directory": ")" + out + R"("},
    "image": {"width": 128, "height": 128, "background": [0.02, 0.02, 0.05]},
    "cameras": {"phi": [-60, 30, 120], "theta": [50], "fov": 30},
    "fields": [{
      "name": "temperature", "range": "auto",
      "transfer_function": {
        "colors": [[0, 0.15, 0.25, 0.7], [0.5, 0.95, 0.45, 0.1], [1, 1, 0.95, 0.6]],
        "opacities": [[0, 4], [0.5, 8], [1, 30]]
      }
    }],
    "lighting": {"model": "phong", "lights": [{"type": "directional", "direction": [-0.6, 0.3, -1]}],
                 "phong": {"ambient": 0.75, "diffuse": 0.35, "specular": 0.15}},
    "trigger": {"every_cycles": )" + std::to_string(kEvery) + R"(}
  })";
}

bool ok(pnb_context ctx, pnb_status s, const char* what, int rank) {
  if (s == PNB_OK) return true;
  std::fprintf(stderr, "penumbra-example-advection-mpi: rank %d: %s failed: %s\n", rank, what, pnb_last_error(ctx));
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  const std::string out = argc > 1 ? argv[1] : "penumbra-example-mpi-db";
  const std::vector<Cube> cubes = domain_cubes();
  const Part part = make_part(cubes, deal_cubes(cubes, ranks), rank);
  Solver solver(part);

  int failures = 0;
  pnb_context ctx = nullptr;
  if (!ok(nullptr, pnb_create_mpi(config_json(out).c_str(), MPI_COMM_WORLD, &ctx), "pnb_create_mpi", rank)) {
    MPI_Finalize();
    return 1;
  }
  pnb_mesh_desc desc PNB_MESH_DESC_INIT;
  desc.points = part.xyz.data();
  desc.point_count = static_cast<std::int64_t>(part.nodes.size());
  desc.point_type = PNB_FLOAT32;
  desc.connectivity = part.tets.data();
  desc.connectivity_count = static_cast<std::int64_t>(part.tets.size());
  desc.index_type = PNB_INT32;
  const std::uint8_t tet = PNB_TETRA;
  desc.cell_types = &tet;
  desc.cell_types_count = 1;
  desc.topology_version = 1;
  std::vector<double> local_temperature(part.nodes.size());
  const double dt = solver.stable_dt();
  for (int cycle = 0; cycle <= kCycles; ++cycle) {
    if (!ok(ctx, pnb_publish_mesh(ctx, &desc, PNB_BORROW), "pnb_publish_mesh", rank)) break;  // collective
    for (std::size_t q = 0; q < part.nodes.size(); ++q) local_temperature[q] = solver.temperature[part.nodes[q]];
    pnb_field_desc t PNB_FIELD_DESC_INIT;
    t.name = "temperature";
    t.values = local_temperature.data();
    t.count = desc.point_count;
    ok(ctx, pnb_publish_field(ctx, &t, PNB_BORROW), "pnb_publish_field", rank);
    if (!ok(ctx, pnb_execute(ctx, cycle * dt, cycle), "pnb_execute", rank)) ++failures;  // collective
    solver.step(dt, part);
  }
  if (!ok(ctx, pnb_finalize(ctx), "pnb_finalize", rank)) ++failures;
  pnb_destroy(ctx);  // collective
  if (rank == 0)
    std::printf("penumbra-example-advection-mpi: %zu cubes on %d ranks (this one: %zu tets), %d cycles, one database: %s/data.csv\n",
                cubes.size(), ranks, part.tets.size() / 4, kCycles + 1, out.c_str());
  MPI_Finalize();
  return failures == 0 ? 0 : 1;
}
