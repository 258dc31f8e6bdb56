// SPDX-License-Identifier: BSD-3-Clause
// examples/advection_diffusion/main.cpp -- a small "solver" that links Penumbra through its C API.
//
// It builds a tet mesh of an L-shaped slab with a square through-hole (a non-convex domain:
// rays leave and re-enter it), then advects a hot blob around the hole while it diffuses, and
// hands every step to Penumbra, which renders some of them into a Cinema database and keeps
// their history compressed in OUTPUT_DIR/store, from which penumbra-view renders new views.
// Usage: penumbra-example-advection [--async] [OUTPUT_DIR]   (default ./penumbra-example-db)
// With --async the steps render on Penumbra's worker thread while the solver goes on.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "penumbra/penumbra.h"

namespace {

// Grid of nx*ny*nz cubes over [0,2]x[0,2]x[0,0.5]; the quadrant x>1, y>1 is cut away (the L)
// and so is a square hole through the middle of the x<1, y<1 quadrant.
constexpr int nx = 24, ny = 24, nz = 6;
constexpr double size_xy = 2.0, size_z = 0.5;
constexpr double h = size_xy / nx;  // cube edge (x and y); z uses size_z / nz = h as well
constexpr double hole_lo = 0.35, hole_hi = 0.65;
// Time loop: cycles 0..kCycles, rendering every kEvery-th from kCameras orbit cameras.
constexpr int kCycles = 176, kEvery = 16, kCameras = 3;
constexpr int kRenderedSteps = kCycles / kEvery + 1;

bool keep_cube(int i, int j) {
  const double x = (i + 0.5) * h, y = (j + 0.5) * h;
  if (x > 1 && y > 1) return false;
  return !(x > hole_lo && x < hole_hi && y > hole_lo && y < hole_hi);
}

int node(int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; }

/// The solver's own mesh: float32 points and int32 ids, as many codes store them.
struct Mesh {
  std::vector<float> xyz;            // compacted: only nodes used by a cell
  std::vector<std::int32_t> tets;    // 4 ids per tet
  std::vector<int> grid_to_point;    // grid node -> point id, or -1 when unused
};

Mesh build_mesh() {
  Mesh m;
  std::vector<int> used((nx + 1) * (ny + 1) * (nz + 1), 0);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        if (keep_cube(i, j))
          for (int c = 0; c < 8; ++c) used[node(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2))] = 1;
  m.grid_to_point.assign(used.size(), -1);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i)
        if (used[node(i, j, k)]) {
          m.grid_to_point[node(i, j, k)] = static_cast<int>(m.xyz.size() / 3);
          m.xyz.insert(m.xyz.end(), {float(i * h), float(j * h), float(k * size_z / nz)});
        }
  // Six tets per cube around the 0-6 diagonal (the same in every cube, so faces match).
  static const int split[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (!keep_cube(i, j)) continue;
        const int v[8] = {node(i, j, k),         node(i + 1, j, k),         node(i + 1, j + 1, k),
                          node(i, j + 1, k),     node(i, j, k + 1),         node(i + 1, j, k + 1),
                          node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)};
        for (const auto& t : split)
          for (int c : t) m.tets.push_back(m.grid_to_point[v[c]]);
      }
  return m;
}

/// Explicit upwind advection + central diffusion on the grid nodes of the domain. Missing
/// neighbours (outside the domain) mirror the node itself: no flux through walls.
struct Solver {
  const Mesh& mesh;
  std::vector<double> temperature;  // per mesh point
  double omega = 2.0;               // angular velocity around the hole's axis
  double kappa = 0.001;             // diffusivity
  double cx = 0.5, cy = 0.5;

  explicit Solver(const Mesh& m) : mesh(m), temperature(m.xyz.size() / 3) {
    for (std::size_t p = 0; p < temperature.size(); ++p) {
      const double dx = m.xyz[3 * p] - 0.5, dy = m.xyz[3 * p + 1] - 0.12, dz = m.xyz[3 * p + 2] - 0.25;
      temperature[p] = 20.0 + 80.0 * std::exp(-(dx * dx + dy * dy + dz * dz) / (2 * 0.12 * 0.12));
    }
  }

  double stable_dt() const {
    const double umax = omega * std::hypot(std::max(cx, size_xy - cx), std::max(cy, size_xy - cy));
    return 0.6 * std::min(h / umax, h * h / (6 * kappa));
  }

  void step(double dt) {
    std::vector<double> next = temperature;
    for (int k = 0; k <= nz; ++k)
      for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) {
          const int p = mesh.grid_to_point[node(i, j, k)];
          if (p < 0) continue;
          auto at = [&](int a, int b, int c) {
            if (a < 0 || b < 0 || c < 0 || a > nx || b > ny || c > nz) return temperature[p];
            const int q = mesh.grid_to_point[node(a, b, c)];
            return q < 0 ? temperature[p] : temperature[q];
          };
          const double x = i * h, y = j * h;
          const double u = -omega * (y - cy), v = omega * (x - cx);
          const double t = temperature[p];
          const double ddx = u > 0 ? t - at(i - 1, j, k) : at(i + 1, j, k) - t;
          const double ddy = v > 0 ? t - at(i, j - 1, k) : at(i, j + 1, k) - t;
          const double lap = at(i + 1, j, k) + at(i - 1, j, k) + at(i, j + 1, k) + at(i, j - 1, k) + at(i, j, k + 1) +
                             at(i, j, k - 1) - 6 * t;
          next[p] = t - dt * (u * ddx + v * ddy) / h + dt * kappa * lap / (h * h);
        }
    temperature.swap(next);
  }
};

std::string config_json(const std::string& out, bool async) {
  return R"({
    "output": {"directory": ")" + out + R"("},
    "image": {"width": 128, "height": 128, "background": [0.02, 0.02, 0.05]},
    "cameras": {"phi": [-60, 30, 120], "theta": [50], "fov": 30},
    "fields": [{
      "name": "temperature",
      "range": "auto",
      "transfer_function": {
        "colors": [[0, 0.15, 0.25, 0.7], [0.5, 0.95, 0.45, 0.1], [1, 1, 0.95, 0.6]],
        "opacities": [[0, 4], [0.5, 8], [1, 30]]
      }
    }],
    "lighting": {
      "model": "light-volume",
      "lights": [{"type": "directional", "direction": [-0.6, 0.3, -1], "color": [1, 0.97, 0.9]}],
      "absorption": 0.08, "scattering": 0.5, "level0_resolution": 48,
      "phong": {"ambient": 0.75, "diffuse": 0.35, "specular": 0.15}
    },
    "trigger": {"every_cycles": )" + std::to_string(kEvery) + R"(},
    "store": {"directory": ")" + out + R"(/store", "every_cycles": )" + std::to_string(kEvery) + R"(, "window": 8})" +
         (async ? R"(,
    "async": true)" : "") + R"(
  })";
}

bool ok(pnb_context ctx, pnb_status s, const char* what) {
  if (s == PNB_OK) return true;
  std::fprintf(stderr, "penumbra-example-advection: %s failed: %s\n", what, pnb_last_error(ctx));
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  bool async = false;
  std::string out = "penumbra-example-db";
  for (int a = 1; a < argc; ++a) {
    if (std::string(argv[a]) == "--async")
      async = true;
    else
      out = argv[a];
  }
  const auto t_start = std::chrono::steady_clock::now();
  const Mesh mesh = build_mesh();
  Solver solver(mesh);

  pnb_context ctx = nullptr;
  if (!ok(nullptr, pnb_create(config_json(out, async).c_str(), &ctx), "pnb_create")) return 1;

  pnb_mesh_desc desc PNB_MESH_DESC_INIT;
  desc.points = mesh.xyz.data();
  desc.point_count = static_cast<std::int64_t>(mesh.xyz.size() / 3);
  desc.point_type = PNB_FLOAT32;
  desc.connectivity = mesh.tets.data();
  desc.connectivity_count = static_cast<std::int64_t>(mesh.tets.size());
  desc.offsets = nullptr;  // every cell is a tet
  desc.index_type = PNB_INT32;
  const std::uint8_t tet = PNB_TETRA;
  desc.cell_types = &tet;
  desc.cell_types_count = 1;
  desc.topology_version = 1;

  std::vector<double> pressure(desc.point_count, 101325.0);  // not in the config: ignored, not copied
  const double dt = solver.stable_dt();
  const int cycles = kCycles;
  double execute_ms = 0;
  int failures = 0;
  for (int cycle = 0; cycle <= cycles; ++cycle) {
    // Republishing an unchanged topology_version each step costs nothing.
    if (!ok(ctx, pnb_publish_mesh(ctx, &desc, PNB_BORROW), "pnb_publish_mesh")) break;
    pnb_field_desc t PNB_FIELD_DESC_INIT, p PNB_FIELD_DESC_INIT;
    t.name = "temperature";
    t.values = solver.temperature.data();
    t.count = desc.point_count;
    p.name = "pressure";
    p.values = pressure.data();
    p.count = desc.point_count;
    ok(ctx, pnb_publish_field(ctx, &t, PNB_BORROW), "pnb_publish_field");
    ok(ctx, pnb_publish_field(ctx, &p, PNB_BORROW), "pnb_publish_field");
    const auto t0 = std::chrono::steady_clock::now();
    // A failed visualization step is reported and the simulation goes on.
    if (!ok(ctx, pnb_execute(ctx, cycle * dt, cycle), "pnb_execute")) ++failures;
    execute_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    solver.step(dt);
  }
  const pnb_status fin = pnb_finalize(ctx);
  ok(ctx, fin, "pnb_finalize");
  pnb_destroy(ctx);
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  std::printf("penumbra-example-advection: %zu tets (L-shaped slab with a hole), %d cycles, %d rendered steps x %d cameras\n",
              mesh.tets.size() / 4, cycles + 1, kRenderedSteps, kCameras);
  std::printf("  Cinema database: %s/data.csv\n", out.c_str());
  std::printf("  field history: %s/store (new views: penumbra-view %s --store %s/store)\n", out.c_str(), out.c_str(),
              out.c_str());
  std::printf("  time in pnb_execute: %.0f ms (%.1f ms per image), total %.2f s\n", execute_ms,
              execute_ms / (kRenderedSteps * kCameras), total_s);
  return failures == 0 && fin == PNB_OK ? 0 : 1;
}
