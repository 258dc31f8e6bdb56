// SPDX-License-Identifier: BSD-3-Clause
// render/src/tet_order.cpp -- Morton order of tet centroids
#include "tet_order.h"

#include <algorithm>
#include <utility>

#include "penumbra/core/morton.h"
#include "penumbra/core/thread_pool.h"

namespace penumbra::render::detail {

namespace {

// Ids 0..count-1 sorted by the Morton code (21 bits per axis, within the mesh's bounds) of
// position(id).
template <class Position>
std::vector<std::int32_t> order_by_morton(const TetMesh& m, std::size_t count, const Position& position) {
  const Vec3d lo = m.bounds.lo, ext = m.bounds.hi - m.bounds.lo;
  double scale[3];
  for (int a = 0; a < 3; ++a) scale[a] = ext[a] > 0 ? 2097151.0 / ext[a] : 0.0;
  std::vector<std::pair<std::uint64_t, std::int32_t>> keyed(count);
  parallel_for(keyed.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Vec3d c = position(i);
      std::uint64_t code = 0;
      for (int a = 0; a < 3; ++a) {
        const double g = std::clamp((c[a] - lo[a]) * scale[a], 0.0, 2097151.0);
        code |= spread_bits_3d(static_cast<std::uint64_t>(g)) << a;
      }
      keyed[i] = {code, static_cast<std::int32_t>(i)};
    }
  });
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::int32_t> order(keyed.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) order[i] = keyed[i].second;
  return order;
}

}  // namespace

std::vector<std::int32_t> morton_order(const TetMesh& m) {
  return order_by_morton(m, m.tets.size(), [&](std::size_t t) {
    Vec3d c{0, 0, 0};
    for (int k = 0; k < 4; ++k) c = c + m.points[static_cast<std::size_t>(m.tets[t][k])];
    return c * 0.25;
  });
}

std::vector<std::int32_t> morton_point_order(const TetMesh& m) {
  return order_by_morton(m, m.points.size(), [&](std::size_t p) { return m.points[p]; });
}

TetMesh with_points_in_order(const TetMesh& mesh, const std::vector<std::int32_t>& order) {
  TetMesh out = mesh;  // tets, neighbours, boundary, bounds and counters as they are
  out.surface = nullptr;
  const std::size_t np = mesh.points.size();
  std::vector<std::int32_t> rank(np);
  for (std::size_t i = 0; i < np; ++i) {
    const auto p = static_cast<std::size_t>(order[i]);
    rank[p] = static_cast<std::int32_t>(i);
    out.points[i] = mesh.points[p];
  }
  parallel_for(out.tets.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t)
      for (auto& v : out.tets[t]) v = rank[static_cast<std::size_t>(v)];
  });
  for (auto& weld : out.welds)
    for (auto& v : weld) v = rank[static_cast<std::size_t>(v)];
  return out;
}

}  // namespace penumbra::render::detail
