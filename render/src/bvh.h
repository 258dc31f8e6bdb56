// SPDX-License-Identifier: BSD-3-Clause
// render/src/bvh.h -- bounding volume hierarchy over boxes, for "every item along a line" queries
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "penumbra/core/vec3.h"

namespace penumbra::render::detail {

/// Binary BVH built by median splits on the widest centroid axis. Leaves hold up to
/// `leaf_size` items; queries visit every item whose box the query line crosses.
class Bvh {
public:
  struct Node {
    double lo[3], hi[3];
    std::int32_t first;  ///< leaf: first slot in items(); inner: index of the left child
    std::int32_t count;  ///< leaf: item count; inner: 0 (right child is first + 1)
  };

  Bvh() = default;
  /// Builds over `boxes`; every box is padded by `pad` on all sides so that line tests that
  /// graze a face are never lost to rounding.
  Bvh(const std::vector<Bounds>& boxes, double pad, int leaf_size = 4);

  /// Calls visit(item) for every item whose box meets the line origin + t * dir with
  /// t in [t_min, t_max] (t_min may be -infinity).
  template <class Visit>
  void for_each_on_line(const Vec3d& origin, const Vec3d& dir, double t_min, double t_max, Visit&& visit) const {
    if (m_nodes.empty()) return;
    double inv[3];
    for (int a = 0; a < 3; ++a) inv[a] = dir[a] != 0.0 ? 1.0 / dir[a] : 0.0;
    std::int32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = m_nodes[static_cast<std::size_t>(stack[--top])];
      if (!hits(n, origin, dir, inv, t_min, t_max)) continue;
      if (n.count > 0) {
        for (std::int32_t i = 0; i < n.count; ++i) visit(m_items[static_cast<std::size_t>(n.first + i)]);
      } else if (top + 2 <= 128) {
        stack[top++] = n.first + 1;
        stack[top++] = n.first;
      }
    }
  }

  std::size_t node_count() const { return m_nodes.size(); }

private:
  static bool hits(const Node& n, const Vec3d& o, const Vec3d& dir, const double inv[3], double t0, double t1) {
    for (int a = 0; a < 3; ++a) {
      if (dir[a] == 0.0) {
        if (o[a] < n.lo[a] || o[a] > n.hi[a]) return false;
        continue;
      }
      double ta = (n.lo[a] - o[a]) * inv[a], tb = (n.hi[a] - o[a]) * inv[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = ta > t0 ? ta : t0;
      t1 = tb < t1 ? tb : t1;
      if (t0 > t1) return false;
    }
    return true;
  }
  void build(std::int32_t node, std::vector<std::int32_t>& ids, std::size_t begin, std::size_t end,
             const std::vector<Bounds>& boxes, const std::vector<Vec3d>& centroids, int leaf_size);

  std::vector<Node> m_nodes;
  std::vector<std::int32_t> m_items;
};

}  // namespace penumbra::render::detail
