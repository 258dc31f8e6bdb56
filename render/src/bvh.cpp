// SPDX-License-Identifier: BSD-3-Clause
// render/src/bvh.cpp -- BVH construction
#include "bvh.h"

#include <algorithm>

namespace penumbra::render::detail {

Bvh::Bvh(const std::vector<Bounds>& boxes, double pad, int leaf_size) {
  if (boxes.empty()) return;
  std::vector<Vec3d> centroids(boxes.size());
  std::vector<std::int32_t> ids(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    centroids[i] = boxes[i].center();
    ids[i] = static_cast<std::int32_t>(i);
  }
  m_nodes.reserve(2 * boxes.size() / static_cast<std::size_t>(leaf_size) + 2);
  m_nodes.push_back({});
  build(0, ids, 0, ids.size(), boxes, centroids, leaf_size);
  m_items = std::move(ids);
  for (auto& n : m_nodes)
    for (int a = 0; a < 3; ++a) {
      n.lo[a] -= pad;
      n.hi[a] += pad;
    }
}

void Bvh::build(std::int32_t node, std::vector<std::int32_t>& ids, std::size_t begin, std::size_t end,
                const std::vector<Bounds>& boxes, const std::vector<Vec3d>& centroids, int leaf_size) {
  Bounds box, cbox;
  for (std::size_t i = begin; i < end; ++i) {
    const auto& b = boxes[static_cast<std::size_t>(ids[i])];
    box.extend(b.lo);
    box.extend(b.hi);
    cbox.extend(centroids[static_cast<std::size_t>(ids[i])]);
  }
  Node& n = m_nodes[static_cast<std::size_t>(node)];
  for (int a = 0; a < 3; ++a) {
    n.lo[a] = box.lo[a];
    n.hi[a] = box.hi[a];
  }
  if (end - begin <= static_cast<std::size_t>(leaf_size)) {
    n.first = static_cast<std::int32_t>(begin);
    n.count = static_cast<std::int32_t>(end - begin);
    return;
  }
  // Median split on the widest centroid axis (boxes with equal centroids split by count).
  const Vec3d extent = cbox.hi - cbox.lo;
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  const std::size_t mid = begin + (end - begin) / 2;
  std::nth_element(ids.begin() + static_cast<std::ptrdiff_t>(begin), ids.begin() + static_cast<std::ptrdiff_t>(mid),
                   ids.begin() + static_cast<std::ptrdiff_t>(end), [&](std::int32_t a, std::int32_t b) {
                     return centroids[static_cast<std::size_t>(a)][axis] < centroids[static_cast<std::size_t>(b)][axis];
                   });
  const auto left = static_cast<std::int32_t>(m_nodes.size());
  n.first = left;
  n.count = 0;
  m_nodes.push_back({});  // invalidates n
  m_nodes.push_back({});
  build(left, ids, begin, mid, boxes, centroids, leaf_size);
  build(left + 1, ids, mid, end, boxes, centroids, leaf_size);
}

}  // namespace penumbra::render::detail
