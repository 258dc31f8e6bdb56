// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level0_sweep.cpp -- ordered upwind sweeps of the level-0 grid
#include "level0_sweep.h"

#include <algorithm>
#include <cmath>

#include "penumbra/core/thread_pool.h"
#include "tet_geometry.h"

namespace penumbra::render::lighting {

void solve_level0(const Level0Grid& grid, const Light& light, double sigma_a, std::vector<float>& rho,
                  std::vector<float>& scratch) {
  const auto& dims = grid.dims();
  const Vec3d h = grid.spacing();
  const auto& tau = grid.tau();
  const auto& mask = grid.mask();
  rho.assign(grid.size(), 0.0f);
  const bool point = light.kind == Light::Kind::point;
  const Vec3d P = light.vector;

  // Octant signs and, per axis, the index of the light's node plane (-1 or dims: none in grid).
  std::array<int, 3> centre{};
  std::vector<std::array<int, 3>> octants;
  Vec3d u{};
  double w_dir[3] = {0, 0, 0}, ds_dir = 0;
  if (!point) {
    u = normalize(light.vector);
    std::array<int, 3> o{};
    double sum = 0;
    for (int a = 0; a < 3; ++a) {
      o[a] = u[a] >= 0 ? 1 : -1;
      centre[a] = o[a] > 0 ? -1 : dims[a];
      w_dir[a] = std::fabs(u[a]) / h[a];
      sum += w_dir[a];
    }
    for (double& w : w_dir) w /= sum;
    ds_dir = 1.0 / sum;
    octants.push_back(o);
    // Half-step attenuation per node: the step's factor is the product of its two ends'.
    scratch.resize(grid.size());
    parallel_for(grid.size(), 65536, [&](std::size_t b, std::size_t e) {
      for (std::size_t id = b; id < e; ++id)
        scratch[id] = static_cast<float>(std::exp(-0.5 * sigma_a * ds_dir * static_cast<double>(tau[id])));
    });
  } else {
    for (int a = 0; a < 3; ++a)
      centre[a] = static_cast<int>(std::clamp(std::lround((P[a] - grid.lo()[a]) / h[a]), -1L, static_cast<long>(dims[a])));
    for (int o = 0; o < 8; ++o) octants.push_back({(o & 1) ? 1 : -1, (o & 2) ? 1 : -1, (o & 4) ? 1 : -1});
  }

  for (const auto& o : octants) {
    int start[3], count[3];
    for (int a = 0; a < 3; ++a) {
      start[a] = o[a] > 0 ? std::max(centre[a], 0) : std::min(centre[a], dims[a] - 1);
      count[a] = o[a] > 0 ? dims[a] - start[a] : start[a] + 1;
    }
    if (count[0] <= 0 || count[1] <= 0 || count[2] <= 0) continue;

    // A directional light has no node plane in the grid: every node reads the same three
    // neighbours, at fixed offsets, and only the rows and the first node of a row on the inflow
    // side read outside (light 1). Each node is the upwind sum over the axes, in axis order, of
    // weight x neighbour's rho x its half-step factor (an axis of weight 0 adds 0 times a finite
    // value), times the node's own factor; no test per node beyond the occluder mask, and
    // kRowsAtOnce rows of an anti-diagonal node by node: each row is a chain of dependent
    // updates (a node reads the one before it), and independent chains side by side overlap.
    const std::ptrdiff_t nx = dims[0], nxy = static_cast<std::ptrdiff_t>(dims[0]) * dims[1];
    const std::ptrdiff_t offset[3] = {-o[0], -o[1] * nx, -o[2] * nxy};
    constexpr int kRowsAtOnce = 4;
    auto directional_rows = [&](const int* j, const int* k, int n) {
      std::size_t first[kRowsAtOnce];
      bool row_outside[kRowsAtOnce];
      for (int r = 0; r < n; ++r) {
        row_outside[r] = (w_dir[1] != 0.0 && (j[r] - o[1] < 0 || j[r] - o[1] >= dims[1])) ||
                         (w_dir[2] != 0.0 && (k[r] - o[2] < 0 || k[r] - o[2] >= dims[2]));
        first[r] = grid.index(start[0], j[r], k[r]);
      }
      for (int ii = 0; ii < count[0]; ++ii)
        for (int r = 0; r < n; ++r) {
          const std::size_t id = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(first[r]) + o[0] * ii);
          if (mask[id] == Level0Mask::occluder) {
            rho[id] = 0.0f;
            continue;
          }
          if (row_outside[r] || (ii == 0 && w_dir[0] != 0.0)) {
            rho[id] = 1.0f;
            continue;
          }
          double real = 0;
          for (int a = 0; a < 3; ++a) {
            // An axis of weight 0 reads the node itself (in the grid, finite) and adds 0.
            const std::size_t nid =
                w_dir[a] != 0.0 ? static_cast<std::size_t>(static_cast<std::ptrdiff_t>(id) + offset[a]) : id;
            real += w_dir[a] * static_cast<double>(rho[nid]) * static_cast<double>(scratch[nid]);
          }
          rho[id] = static_cast<float>(flush(real * static_cast<double>(scratch[id])));
        }
    };
    // A point light's row: the upwind neighbours and their weights change from node to node.
    auto point_row = [&](int j, int k) {
      int s[3], idx[3] = {0, j, k};
      s[1] = j == centre[1] ? 0 : o[1];
      s[2] = k == centre[2] ? 0 : o[2];
      for (int ii = 0; ii < count[0]; ++ii) {
        const int i = start[0] + o[0] * ii;
        idx[0] = i;
        s[0] = i == centre[0] ? 0 : o[0];
        const std::size_t id = grid.index(i, j, k);
        if (mask[id] == Level0Mask::occluder) {
          rho[id] = 0.0f;
          continue;
        }
        const Vec3d r = grid.position(i, j, k) - P;
        const double dist = length(r);
        if (dist == 0.0) {
          rho[id] = 1.0f;
          continue;
        }
        double w[3], sum = 0;
        for (int a = 0; a < 3; ++a) {
          w[a] = s[a] != 0 ? std::fabs(r[a]) / dist / h[a] : 0.0;
          sum += w[a];
        }
        const double ti = static_cast<double>(tau[id]);
        double value = 0;
        if (sum == 0.0) {
          value = std::exp(-sigma_a * ti * dist);  // the light's own node
        } else {
          const double ds = std::min(1.0 / sum, dist);
          for (int a = 0; a < 3; ++a) {
            if (w[a] == 0.0) continue;
            const int nb = idx[a] - s[a];
            if (nb < 0 || nb >= dims[a]) {
              value = 1.0;
              break;
            }
            int nidx[3] = {idx[0], idx[1], idx[2]};
            nidx[a] = nb;
            const std::size_t nid = grid.index(nidx[0], nidx[1], nidx[2]);
            value += w[a] / sum * static_cast<double>(rho[nid]) *
                     std::exp(-0.5 * sigma_a * ds * (ti + static_cast<double>(tau[nid])));
          }
        }
        rho[id] = static_cast<float>(flush(value));
      }
    };

    // Rows (j, k) on one anti-diagonal depend only on the previous anti-diagonal.
    const int diagonals = count[1] + count[2] - 1;
    for (int m = 0; m < diagonals; ++m) {
      const int jj0 = std::max(0, m - count[2] + 1), jj1 = std::min(count[1] - 1, m);
      const int rows = jj1 - jj0 + 1;
      auto run = [&](std::size_t b, std::size_t e) {
        for (std::size_t r = b; r < e;) {
          int j[kRowsAtOnce], k[kRowsAtOnce], n = 0;
          for (; n < kRowsAtOnce && r < e; ++n, ++r) {
            const int jj = jj0 + static_cast<int>(r);
            j[n] = start[1] + o[1] * jj;
            k[n] = start[2] + o[2] * (m - jj);
          }
          if (point)
            for (int q = 0; q < n; ++q) point_row(j[q], k[q]);
          else
            directional_rows(j, k, n);
        }
      };
      if (static_cast<long>(rows) * count[0] < 8192)
        run(0, static_cast<std::size_t>(rows));
      else
        parallel_for(static_cast<std::size_t>(rows), 4, run);
    }
  }
}

}  // namespace penumbra::render::lighting
