// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level1_order.cpp -- the mesh vertices grouped along a light (VertexOrder)
#include <algorithm>
#include <cmath>

#include "level1_solve.h"
#include "penumbra/core/thread_pool.h"

namespace penumbra::render::lighting {
namespace {

// Points per block when keys are computed and slabs counted in parallel.
constexpr std::size_t kBlock = 1 << 14;

// Whether point p belongs to a tet (a mesh may keep points no tet uses).
bool in_a_tet(const Level1Topology& topology, std::size_t p) {
  return topology.tet_offsets[p] != topology.tet_offsets[p + 1];
}

// The slabs [k0 + g width, k0 + (g + 1) width) of the points' keys along the light.
struct Slabs {
  const std::vector<double>& key;
  double k0, width;
  std::size_t of(std::size_t p) const { return static_cast<std::size_t>(std::floor((key[p] - k0) / width)); }
};

// The smallest and largest key of the points in tets, and how many they are.
struct KeyRange {
  double lo, hi;
  std::size_t used;
};

// Every point's key along the light (directional: x . u; point: its distance from the light) and
// its path length to the light through the mesh bounds, in parallel over fixed blocks of points.
KeyRange compute_keys(const TetMesh& mesh, const Level1Topology& topology, const Light& light, VertexOrder& order) {
  const std::size_t np = mesh.points.size();
  const Vec3d u = light.kind == Light::Kind::directional ? normalize(light.vector) : Vec3d{};
  const std::size_t blocks = (np + kBlock - 1) / kBlock;
  std::vector<double> block_lo(blocks, HUGE_VAL), block_hi(blocks, -HUGE_VAL);
  std::vector<std::size_t> block_used(blocks, 0);
  order.key.resize(np);
  std::vector<double>& key = order.key;
  order.path_length.resize(np);
  parallel_for(blocks, 1, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      // Kept in locals: the threads' entries of block_lo etc. share cache lines.
      double lo = HUGE_VAL, hi = -HUGE_VAL;
      std::size_t n = 0;
      for (std::size_t p = b * kBlock; p < std::min(np, (b + 1) * kBlock); ++p) {
        key[p] = light.kind == Light::Kind::directional ? dot(mesh.points[p], u) : length(mesh.points[p] - light.vector);
        order.path_length[p] = box_path_length(mesh.bounds, mesh.points[p], light);
        if (!in_a_tet(topology, p)) continue;
        ++n;
        lo = std::min(lo, key[p]);
        hi = std::max(hi, key[p]);
      }
      block_lo[b] = lo;
      block_hi[b] = hi;
      block_used[b] = n;
    }
  });
  KeyRange range{*std::min_element(block_lo.begin(), block_lo.end()),
                 *std::max_element(block_hi.begin(), block_hi.end()), 0};
  for (std::size_t n : block_used) range.used += n;
  return range;
}

// The groups by a sort of the points: for steps far below the point spacing (a user's choice),
// where there are more slabs than points.
void order_by_sort(const Level1Topology& topology, const Slabs& slabs, VertexOrder& order) {
  const std::size_t np = order.key.size();
  order.vertices.clear();
  for (std::size_t p = 0; p < np; ++p)
    if (in_a_tet(topology, p)) order.vertices.push_back(static_cast<std::int32_t>(p));
  std::sort(order.vertices.begin(), order.vertices.end(), [&](std::int32_t a, std::int32_t b) {
    const std::size_t sa = slabs.of(static_cast<std::size_t>(a)), sb = slabs.of(static_cast<std::size_t>(b));
    return sa != sb ? sa < sb : a < b;
  });
  for (std::size_t i = 0; i < order.vertices.size(); ++i)
    if (i + 1 == order.vertices.size() || slabs.of(static_cast<std::size_t>(order.vertices[i])) !=
                                              slabs.of(static_cast<std::size_t>(order.vertices[i + 1])))
      order.group_end.push_back(i + 1);
  for (std::size_t g = 0, begin = 0; g < order.group_end.size(); begin = order.group_end[g++])
    for (std::size_t i = begin; i < order.group_end[g]; ++i)
      order.group_of[static_cast<std::size_t>(order.vertices[i])] = static_cast<std::int32_t>(g);
}

// Turns the per-[part][slab] counts in `at` into first positions, summed in (slab, part) order,
// and ends a group at every slab that has points. Returns each slab's group (-1: empty).
std::vector<std::int32_t> scan_slab_counts(std::size_t parts, std::size_t slab_count, std::vector<std::size_t>& at,
                                           std::vector<std::size_t>& group_end) {
  std::vector<std::int32_t> group_of_slab(slab_count, -1);
  std::size_t sum = 0;
  for (std::size_t slab = 0; slab < slab_count; ++slab) {
    const std::size_t before = sum;
    for (std::size_t b = 0; b < parts; ++b) {
      const std::size_t n = at[b * slab_count + slab];
      at[b * slab_count + slab] = sum;
      sum += n;
    }
    if (sum > before) {
      group_of_slab[slab] = static_cast<std::int32_t>(group_end.size());
      group_end.push_back(sum);
    }
  }
  return group_of_slab;
}

// The groups by a bucket count, no sort: each part of the points counts its points per slab; the
// counts, summed in (slab, part) order, give each part where its points of each slab go, so the
// parts place theirs in parallel and a slab keeps the points' order. With very many slabs (a
// step near the point spacing) the counts would outgrow the points: one part then.
void order_by_counting(const Level1Topology& topology, const Slabs& slabs, double span, std::size_t used,
                       VertexOrder& order) {
  const std::size_t np = order.key.size();
  const std::size_t blocks = (np + kBlock - 1) / kBlock;
  const std::size_t slab_count = static_cast<std::size_t>(span) + 1;
  const std::size_t parts = slab_count * blocks <= 4 * np ? blocks : 1;
  const std::size_t part_size = parts == 1 ? np : kBlock;
  order.vertices.resize(used);
  // [part][slab], so that the threads' counters never share a cache line: first position, after
  // the scan.
  std::vector<std::size_t> at(parts * slab_count, 0);
  parallel_for(parts, 1, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b)
      for (std::size_t p = b * part_size; p < std::min(np, (b + 1) * part_size); ++p)
        if (in_a_tet(topology, p)) ++at[b * slab_count + slabs.of(p)];
  });
  const std::vector<std::int32_t> group_of_slab = scan_slab_counts(parts, slab_count, at, order.group_end);
  parallel_for(parts, 1, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b)
      for (std::size_t p = b * part_size; p < std::min(np, (b + 1) * part_size); ++p)
        if (in_a_tet(topology, p)) {
          const std::size_t slab = slabs.of(p);
          order.vertices[at[b * slab_count + slab]++] = static_cast<std::int32_t>(p);
          order.group_of[p] = group_of_slab[slab];
        }
  });
}

}  // namespace

VertexOrder order_vertices(const TetMesh& mesh, const Level1Topology& topology, const Light& light, double step,
                           VertexOrder reuse) {
  // This runs as one piece of a frame budget, so it avoids sorting where it can: keys and slabs
  // by a bucket count, in parallel over fixed blocks of points. Within a slab the points keep
  // their own order (any order is valid there): the light volume numbers them along a Morton
  // curve, so consecutive walks stay in the same part of the mesh, and of memory.
  VertexOrder order = std::move(reuse);
  order.vertices.clear();
  order.group_end.clear();
  const KeyRange range = compute_keys(mesh, topology, light, order);
  order.group_of.assign(mesh.points.size(), -1);
  if (range.used == 0) return order;
  // Groups are the slabs [k0 + g h / 2, k0 + (g + 1) h / 2) of the key (k0 its smallest value).
  const Slabs slabs{order.key, range.lo, 0.5 * step};
  const double span = (range.hi - range.lo) / slabs.width;
  if (span < 2.0 * static_cast<double>(range.used))
    order_by_counting(topology, slabs, span, range.used, order);
  else
    order_by_sort(topology, slabs, order);
  return order;
}

}  // namespace penumbra::render::lighting
