// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level0_sweep.cpp -- ordered upwind sweeps of the level-0 grid
#include "level0_sweep.h"

#include <algorithm>
#include <cmath>

#include "penumbra/core/thread_pool.h"
#include "tet_geometry.h"

namespace penumbra::render::lighting {
namespace {

// Rows of an anti-diagonal swept node by node side by side: each row is a chain of dependent
// updates (a node reads the one before it), and independent chains side by side overlap.
constexpr int kRowsAtOnce = 4;

// One octant of a sweep: its direction per axis, its first node and node count per axis, and
// the index offsets of a node's upwind neighbours.
struct Octant {
  std::array<int, 3> sign;
  int start[3], count[3];
  std::ptrdiff_t offset[3];
};

// One light's sweep over the grid (see solve_level0).
class Level0Sweep {
public:
  Level0Sweep(const Level0Grid& grid, const Light& light, double sigma_a, std::vector<float>& rho,
              std::vector<float>& scratch)
      : m_grid(grid),
        m_dims(grid.dims()),
        m_h(grid.spacing()),
        m_tau(grid.tau()),
        m_mask(grid.mask()),
        m_light(light),
        m_point(light.kind == Light::Kind::point),
        m_sigma_a(sigma_a),
        m_rho(rho),
        m_scratch(scratch) {}

  void run() {
    m_rho.assign(m_grid.size(), 0.0f);
    if (m_point)
      set_up_point();
    else
      set_up_directional();
    for (const auto& o : m_octants) sweep_octant(o);
  }

private:
  void set_up_directional();
  void set_up_point();
  void sweep_octant(const std::array<int, 3>& sign);
  void sweep_rows(const Octant& o, int m, int jj0, std::size_t b, std::size_t e);
  void directional_rows(const Octant& o, const int* j, const int* k, int n);
  void point_row(const Octant& o, int j, int k);
  float point_node(const int idx[3], const int s[3], std::size_t id) const;

  const Level0Grid& m_grid;
  const std::array<int, 3>& m_dims;
  const Vec3d m_h;
  const std::vector<float>& m_tau;
  const std::vector<Level0Mask>& m_mask;
  const Light& m_light;
  const bool m_point;
  const double m_sigma_a;
  std::vector<float>& m_rho;
  std::vector<float>& m_scratch;  // a directional light: each node's half-step attenuation
  // Per axis, the index of the light's node plane (-1 or dims: none in the grid).
  std::array<int, 3> m_centre{};
  std::vector<std::array<int, 3>> m_octants;
  double m_w_dir[3] = {0, 0, 0}, m_ds_dir = 0;  // a directional light's upwind weights and step
};

// One octant along the light. Each node's half-step attenuation is precomputed: the step's
// factor is the product of its two ends'.
void Level0Sweep::set_up_directional() {
  const Vec3d u = normalize(m_light.vector);
  std::array<int, 3> o{};
  double sum = 0;
  for (int a = 0; a < 3; ++a) {
    o[a] = u[a] >= 0 ? 1 : -1;
    m_centre[a] = o[a] > 0 ? -1 : m_dims[a];
    m_w_dir[a] = std::fabs(u[a]) / m_h[a];
    sum += m_w_dir[a];
  }
  for (double& w : m_w_dir) w /= sum;
  m_ds_dir = 1.0 / sum;
  m_octants.push_back(o);
  m_scratch.resize(m_grid.size());
  const double factor = -0.5 * m_sigma_a * m_ds_dir;
  parallel_for(m_grid.size(), 65536, [&](std::size_t b, std::size_t e) {
    for (std::size_t id = b; id < e; ++id) m_scratch[id] = static_cast<float>(std::exp(factor * static_cast<double>(m_tau[id])));
  });
}

// Eight octants outward from the node nearest the light.
void Level0Sweep::set_up_point() {
  const Vec3d& p = m_light.vector;
  for (int a = 0; a < 3; ++a)
    m_centre[a] =
        static_cast<int>(std::clamp(std::lround((p[a] - m_grid.lo()[a]) / m_h[a]), -1L, static_cast<long>(m_dims[a])));
  for (int o = 0; o < 8; ++o) m_octants.push_back({(o & 1) ? 1 : -1, (o & 2) ? 1 : -1, (o & 4) ? 1 : -1});
}

// Rows (j, k) on one anti-diagonal depend only on the previous anti-diagonal, so the rows of an
// anti-diagonal run in parallel.
void Level0Sweep::sweep_octant(const std::array<int, 3>& sign) {
  Octant o{sign, {}, {}, {}};
  for (int a = 0; a < 3; ++a) {
    o.start[a] = sign[a] > 0 ? std::max(m_centre[a], 0) : std::min(m_centre[a], m_dims[a] - 1);
    o.count[a] = sign[a] > 0 ? m_dims[a] - o.start[a] : o.start[a] + 1;
  }
  if (o.count[0] <= 0 || o.count[1] <= 0 || o.count[2] <= 0) return;
  const std::ptrdiff_t nx = m_dims[0], nxy = static_cast<std::ptrdiff_t>(m_dims[0]) * m_dims[1];
  o.offset[0] = -sign[0];
  o.offset[1] = -sign[1] * nx;
  o.offset[2] = -sign[2] * nxy;
  const int diagonals = o.count[1] + o.count[2] - 1;
  for (int m = 0; m < diagonals; ++m) {
    const int jj0 = std::max(0, m - o.count[2] + 1), jj1 = std::min(o.count[1] - 1, m);
    const int rows = jj1 - jj0 + 1;
    auto run = [&](std::size_t b, std::size_t e) { sweep_rows(o, m, jj0, b, e); };
    if (static_cast<long>(rows) * o.count[0] < 8192)
      run(0, static_cast<std::size_t>(rows));
    else
      parallel_for(static_cast<std::size_t>(rows), 4, run);
  }
}

// Rows [b, e) of anti-diagonal m (its first row jj0), kRowsAtOnce at a time.
void Level0Sweep::sweep_rows(const Octant& o, int m, int jj0, std::size_t b, std::size_t e) {
  for (std::size_t r = b; r < e;) {
    int j[kRowsAtOnce], k[kRowsAtOnce], n = 0;
    for (; n < kRowsAtOnce && r < e; ++n, ++r) {
      const int jj = jj0 + static_cast<int>(r);
      j[n] = o.start[1] + o.sign[1] * jj;
      k[n] = o.start[2] + o.sign[2] * (m - jj);
    }
    if (m_point)
      for (int q = 0; q < n; ++q) point_row(o, j[q], k[q]);
    else
      directional_rows(o, j, k, n);
  }
}

// A directional light has no node plane in the grid: every node reads the same three
// neighbours, at fixed offsets, and only the rows and the first node of a row on the inflow
// side read outside (light 1). Each node is the upwind sum over the axes, in axis order, of
// weight x neighbour's rho x its half-step factor (an axis of weight 0 adds 0 times a finite
// value), times the node's own factor; no test per node beyond the occluder mask, and n rows
// node by node.
void Level0Sweep::directional_rows(const Octant& o, const int* j, const int* k, int n) {
  std::size_t first[kRowsAtOnce];
  bool row_outside[kRowsAtOnce];
  for (int r = 0; r < n; ++r) {
    row_outside[r] = (m_w_dir[1] != 0.0 && (j[r] - o.sign[1] < 0 || j[r] - o.sign[1] >= m_dims[1])) ||
                     (m_w_dir[2] != 0.0 && (k[r] - o.sign[2] < 0 || k[r] - o.sign[2] >= m_dims[2]));
    first[r] = m_grid.index(o.start[0], j[r], k[r]);
  }
  for (int ii = 0; ii < o.count[0]; ++ii)
    for (int r = 0; r < n; ++r) {
      const std::size_t id = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(first[r]) + o.sign[0] * ii);
      if (m_mask[id] == Level0Mask::occluder) {
        m_rho[id] = 0.0f;
        continue;
      }
      if (row_outside[r] || (ii == 0 && m_w_dir[0] != 0.0)) {
        m_rho[id] = 1.0f;
        continue;
      }
      double real = 0;
      for (int a = 0; a < 3; ++a) {
        // An axis of weight 0 reads the node itself (in the grid, finite) and adds 0.
        const std::size_t nid =
            m_w_dir[a] != 0.0 ? static_cast<std::size_t>(static_cast<std::ptrdiff_t>(id) + o.offset[a]) : id;
        real += m_w_dir[a] * static_cast<double>(m_rho[nid]) * static_cast<double>(m_scratch[nid]);
      }
      m_rho[id] = static_cast<float>(flush(real * static_cast<double>(m_scratch[id])));
    }
}

// A point light's row: the upwind neighbours and their weights change from node to node.
void Level0Sweep::point_row(const Octant& o, int j, int k) {
  int s[3], idx[3] = {0, j, k};
  s[1] = j == m_centre[1] ? 0 : o.sign[1];
  s[2] = k == m_centre[2] ? 0 : o.sign[2];
  for (int ii = 0; ii < o.count[0]; ++ii) {
    const int i = o.start[0] + o.sign[0] * ii;
    idx[0] = i;
    s[0] = i == m_centre[0] ? 0 : o.sign[0];
    const std::size_t id = m_grid.index(i, j, k);
    m_rho[id] = m_mask[id] == Level0Mask::occluder ? 0.0f : point_node(idx, s, id);
  }
}

// Node idx of a point light's sweep, s its upwind direction per axis (0: the light's plane).
float Level0Sweep::point_node(const int idx[3], const int s[3], std::size_t id) const {
  const Vec3d r = m_grid.position(idx[0], idx[1], idx[2]) - m_light.vector;
  const double dist = length(r);
  if (dist == 0.0) return 1.0f;
  double w[3], sum = 0;
  for (int a = 0; a < 3; ++a) {
    w[a] = s[a] != 0 ? std::fabs(r[a]) / dist / m_h[a] : 0.0;
    sum += w[a];
  }
  const double ti = static_cast<double>(m_tau[id]);
  if (sum == 0.0) return static_cast<float>(flush(std::exp(-m_sigma_a * ti * dist)));  // the light's own node
  const double ds = std::min(1.0 / sum, dist);
  double value = 0;
  for (int a = 0; a < 3; ++a) {
    if (w[a] == 0.0) continue;
    const int nb = idx[a] - s[a];
    if (nb < 0 || nb >= m_dims[a]) {
      value = 1.0;
      break;
    }
    int nidx[3] = {idx[0], idx[1], idx[2]};
    nidx[a] = nb;
    const std::size_t nid = m_grid.index(nidx[0], nidx[1], nidx[2]);
    value += w[a] / sum * static_cast<double>(m_rho[nid]) *
             std::exp(-0.5 * m_sigma_a * ds * (ti + static_cast<double>(m_tau[nid])));
  }
  return static_cast<float>(flush(value));
}

}  // namespace

void solve_level0(const Level0Grid& grid, const Light& light, double sigma_a, std::vector<float>& rho,
                  std::vector<float>& scratch) {
  Level0Sweep(grid, light, sigma_a, rho, scratch).run();
}

}  // namespace penumbra::render::lighting
