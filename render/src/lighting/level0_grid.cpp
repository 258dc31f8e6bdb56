// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level0_grid.cpp -- level-0 node location, resampling and interpolation
#include "level0_grid.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "tet_geometry.h"
#include "shader_constants.h"

namespace penumbra::render::lighting {

// The shaders read the mask by these values (shader_constants.h).
static_assert(static_cast<unsigned>(Level0Mask::outside) == shader::kMaskOutside &&
              static_cast<unsigned>(Level0Mask::occluder) == shader::kMaskOccluder);
namespace {

// Affine map from a point to the barycentric coordinates (l1, l2, l3) of a tet; l0 = 1 - sum.
struct BaryMap {
  Vec3d origin;
  Vec3d row[3];
  explicit BaryMap(const Vec3d q[4]) : origin(q[0]) {
    const Vec3d e1 = q[1] - q[0], e2 = q[2] - q[0], e3 = q[3] - q[0];
    const double inv = 1.0 / dot(e1, cross(e2, e3));
    row[0] = cross(e2, e3) * inv;
    row[1] = cross(e3, e1) * inv;
    row[2] = cross(e1, e2) * inv;
  }
  // Smallest barycentric coordinate of p (>= 0 inside).
  double min_coordinate(const Vec3d& p, double l[4]) const {
    const Vec3d r = p - origin;
    l[1] = dot(row[0], r);
    l[2] = dot(row[1], r);
    l[3] = dot(row[2], r);
    l[0] = 1.0 - l[1] - l[2] - l[3];
    return std::min(std::min(l[0], l[1]), std::min(l[2], l[3]));
  }
};

// Nodes a rounding error outside a tet still belong to it: nodes on the mesh boundary are inside.
constexpr double kInsideSlack = 1e-9;

}  // namespace

std::array<int, 3> Level0Grid::choose_dims(const Bounds& bounds, int resolution, std::size_t budget_bytes,
                                           std::size_t lights) {
  require(resolution >= 2, "LightVolume: level0_resolution = " + std::to_string(resolution) + "; expected >= 2");
  const Vec3d ext = bounds.hi - bounds.lo;
  const double longest = std::max(ext.x, std::max(ext.y, ext.z));
  const std::size_t per_node = bytes_per_node(lights);
  for (int r = resolution; r >= 2; r = std::min(r - 1, static_cast<int>(r * 0.97))) {
    std::array<int, 3> dims{};
    std::size_t nodes = 1;
    for (int a = 0; a < 3; ++a) {
      dims[a] = std::max(2, static_cast<int>(std::ceil((r - 1) * ext[a] / longest - 1e-9)) + 1);
      nodes *= static_cast<std::size_t>(dims[a]);
    }
    if (nodes * per_node <= budget_bytes) {
      require(r >= 4, "LightVolume: level0_memory_budget_bytes = " + std::to_string(budget_bytes) +
                          " holds fewer than 4 level-0 nodes per axis (" + std::to_string(per_node) +
                          " bytes per node); expected a larger budget");
      return dims;
    }
  }
  throw Error(ErrorCode::invalid_argument, "LightVolume: level0_memory_budget_bytes = " +
                                               std::to_string(budget_bytes) +
                                               " cannot hold a level-0 grid; expected a larger budget");
}

Level0Grid::Level0Grid(const TetMesh& mesh, const Bounds& bounds, std::array<int, 3> dims,
                       const std::vector<Bounds>& occluders)
    : m_dims(dims), m_lo(bounds.lo) {
  for (int a = 0; a < 3; ++a) m_h[a] = (bounds.hi[a] - bounds.lo[a]) / (dims[a] - 1);
  const std::size_t n = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
  m_node_tet.assign(n, -1);
  m_mask.assign(n, Level0Mask::outside);
  m_tau.assign(n, 0.0f);

  // Bin the tets by the node layers (k) their boxes cover; each layer is then filled by one
  // thread, so every node is written by one thread in a fixed order (deterministic).
  struct Range {
    int lo[3], hi[3];
  };
  std::vector<Range> ranges(mesh.tets.size());
  std::vector<std::vector<std::int32_t>> layers(static_cast<std::size_t>(dims[2]));
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    Bounds b;
    for (int k = 0; k < 4; ++k) b.extend(mesh.points[static_cast<std::size_t>(mesh.tets[t][k])]);
    Range& r = ranges[t];
    for (int a = 0; a < 3; ++a) {
      const double slack = 1e-9 * m_h[a];
      r.lo[a] = std::max(0, static_cast<int>(std::ceil((b.lo[a] - m_lo[a] - slack) / m_h[a])));
      r.hi[a] = std::min(dims[a] - 1, static_cast<int>(std::floor((b.hi[a] - m_lo[a] + slack) / m_h[a])));
    }
    for (int k = r.lo[2]; k <= r.hi[2]; ++k) layers[static_cast<std::size_t>(k)].push_back(static_cast<std::int32_t>(t));
  }
  std::vector<float> best(n, -HUGE_VALF);
  parallel_for(static_cast<std::size_t>(dims[2]), 1, [&](std::size_t k0, std::size_t k1) {
    for (std::size_t k = k0; k < k1; ++k)
      for (std::int32_t t : layers[k]) {
        const auto& tv = mesh.tets[static_cast<std::size_t>(t)];
        Vec3d q[4];
        for (int c = 0; c < 4; ++c) q[c] = mesh.points[static_cast<std::size_t>(tv[c])];
        const BaryMap map(q);
        const Range& r = ranges[static_cast<std::size_t>(t)];
        for (int j = r.lo[1]; j <= r.hi[1]; ++j)
          for (int i = r.lo[0]; i <= r.hi[0]; ++i) {
            double l[4];
            const double m = map.min_coordinate(position(i, j, static_cast<int>(k)), l);
            const std::size_t id = index(i, j, static_cast<int>(k));
            // The tet holding the node most deeply wins; ties keep the first (lowest id).
            if (m >= -kInsideSlack && static_cast<float>(m) > best[id]) {
              best[id] = static_cast<float>(m);
              m_node_tet[id] = t;
            }
          }
      }
  });
  for (std::size_t id = 0; id < n; ++id)
    if (m_node_tet[id] >= 0) m_mask[id] = Level0Mask::inside;
  for (const Bounds& box : occluders)
    for (int k = 0; k < dims[2]; ++k)
      for (int j = 0; j < dims[1]; ++j)
        for (int i = 0; i < dims[0]; ++i)
          if (inside_box(position(i, j, k), box)) m_mask[index(i, j, k)] = Level0Mask::occluder;
}

void Level0Grid::resample(const TetMesh& mesh, const std::vector<float>& scalars, const ExtinctionTable& table) {
  const int nx = m_dims[0], ny = m_dims[1];
  parallel_for(static_cast<std::size_t>(m_dims[2]) * ny, 4, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t r = r0; r < r1; ++r) {
      const int j = static_cast<int>(r % ny), k = static_cast<int>(r / ny);
      for (int i = 0; i < nx; ++i) {
        const std::size_t id = index(i, j, k);
        const std::int32_t t = m_node_tet[id];
        if (t < 0) {
          m_tau[id] = 0.0f;
          continue;
        }
        const auto& tv = mesh.tets[static_cast<std::size_t>(t)];
        const auto w = convex_weights(barycentric(mesh, t, position(i, j, k)));
        double s = 0;
        for (int c = 0; c < 4; ++c) s += w[c] * static_cast<double>(scalars[static_cast<std::size_t>(tv[c])]);
        m_tau[id] = static_cast<float>(table.tau(s));
      }
    }
  });
}

bool Level0Grid::combine(const std::function<void(std::vector<float>&, std::vector<Level0Mask>&)>& combine) {
  const std::size_t n = m_mask.size();
  std::vector<Level0Mask> before = m_mask;
  combine(m_tau, m_mask);
  if (m_tau.size() != n || m_mask.size() != n)
    throw Error(ErrorCode::internal_error, "LightVolume::combine_level0: the combination resized the level-0 grid (" +
                                               std::to_string(n) + " nodes)");
  return m_mask != before;
}

Level0Grid::Cell Level0Grid::locate(const Vec3d& p) const {
  Cell c{};
  for (int a = 0; a < 3; ++a) {
    double u = (p[a] - m_lo[a]) / m_h[a];
    u = std::clamp(u, 0.0, static_cast<double>(m_dims[a] - 1));
    int i = std::min(static_cast<int>(u), m_dims[a] - 2);
    c.i[a] = i;
    c.f[a] = u - i;
  }
  return c;
}

double Level0Grid::sample(const std::vector<float>& field, const Vec3d& p) const {
  const Cell c = locate(p);
  double sum = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const int dx = corner & 1, dy = (corner >> 1) & 1, dz = corner >> 2;
    const double w = (dx ? c.f[0] : 1 - c.f[0]) * (dy ? c.f[1] : 1 - c.f[1]) * (dz ? c.f[2] : 1 - c.f[2]);
    sum += w * static_cast<double>(field[index(c.i[0] + dx, c.i[1] + dy, c.i[2] + dz)]);
  }
  return sum;
}

double Level0Grid::sample_prefer_outside(const std::vector<float>& field, const Vec3d& p) const {
  const Cell c = locate(p);
  double sum = 0, wsum = 0, sum_out = 0, wsum_out = 0;
  bool any_outside = false;
  for (int corner = 0; corner < 8; ++corner) {
    const int dx = corner & 1, dy = (corner >> 1) & 1, dz = corner >> 2;
    const double w = (dx ? c.f[0] : 1 - c.f[0]) * (dy ? c.f[1] : 1 - c.f[1]) * (dz ? c.f[2] : 1 - c.f[2]);
    const std::size_t id = index(c.i[0] + dx, c.i[1] + dy, c.i[2] + dz);
    const double v = static_cast<double>(field[id]);
    sum += w * v;
    wsum += w;
    if (m_mask[id] == Level0Mask::outside) {
      any_outside = true;
      // A tiny floor keeps an outside corner usable when p sits exactly on the opposite face.
      const double wo = std::max(w, 1e-12);
      sum_out += wo * v;
      wsum_out += wo;
    }
  }
  return any_outside ? sum_out / wsum_out : sum / wsum;
}

}  // namespace penumbra::render::lighting
