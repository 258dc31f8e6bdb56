// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/gpu_mesh_layout.cpp -- packing a TetMesh for the GPU ray caster
#include "gpu_mesh_layout.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "tet_order.h"
#include "walk_mesh.h"

namespace penumbra::render::gpu {
namespace {

using detail::kFaceVertices;  // the CPU walk's face order, so both casters see the same faces
constexpr int kLeafSize = 4;

struct Box {
  float lo[3], hi[3];
};

class BvhBuilder {
public:
  BvhBuilder(const std::vector<Box>& boxes, float pad, std::vector<BvhNode>& nodes, std::vector<std::int32_t>& order)
      : m_boxes(boxes), m_pad(pad), m_nodes(nodes), m_order(order) {
    m_order.resize(boxes.size());
    std::iota(m_order.begin(), m_order.end(), 0);
    m_nodes.clear();
    if (boxes.empty()) return;
    m_nodes.push_back({});
    build(0, 0, boxes.size());
  }

private:
  void build(std::size_t node, std::size_t begin, std::size_t end) {
    BvhNode n{};
    float clo[3], chi[3];
    for (int a = 0; a < 3; ++a) {
      n.lo[a] = clo[a] = std::numeric_limits<float>::infinity();
      n.hi[a] = chi[a] = -std::numeric_limits<float>::infinity();
    }
    for (std::size_t i = begin; i < end; ++i) {
      const Box& b = m_boxes[static_cast<std::size_t>(m_order[i])];
      for (int a = 0; a < 3; ++a) {
        n.lo[a] = std::min(n.lo[a], b.lo[a]);
        n.hi[a] = std::max(n.hi[a], b.hi[a]);
        const float c = 0.5f * (b.lo[a] + b.hi[a]);
        clo[a] = std::min(clo[a], c);
        chi[a] = std::max(chi[a], c);
      }
    }
    // Padded so that a ray grazing a face is never lost to the rounding of the slab test.
    for (int a = 0; a < 3; ++a) {
      n.lo[a] -= m_pad;
      n.hi[a] += m_pad;
    }
    if (end - begin <= static_cast<std::size_t>(kLeafSize)) {
      n.first = static_cast<std::int32_t>(begin);
      n.count = static_cast<std::int32_t>(end - begin);
      m_nodes[node] = n;
      return;
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (chi[a] - clo[a] > chi[axis] - clo[axis]) axis = a;
    const std::size_t mid = begin + (end - begin) / 2;
    std::nth_element(m_order.begin() + static_cast<std::ptrdiff_t>(begin), m_order.begin() + static_cast<std::ptrdiff_t>(mid),
                     m_order.begin() + static_cast<std::ptrdiff_t>(end), [&](std::int32_t x, std::int32_t y) {
                       const Box& bx = m_boxes[static_cast<std::size_t>(x)];
                       const Box& by = m_boxes[static_cast<std::size_t>(y)];
                       return bx.lo[axis] + bx.hi[axis] < by.lo[axis] + by.hi[axis];
                     });
    const std::size_t left = m_nodes.size();
    m_nodes.push_back({});
    m_nodes.push_back({});
    n.first = static_cast<std::int32_t>(left);
    n.count = 0;
    m_nodes[node] = n;
    build(left, begin, mid);
    build(left + 1, mid, end);
  }

  const std::vector<Box>& m_boxes;
  float m_pad;
  std::vector<BvhNode>& m_nodes;
  std::vector<std::int32_t>& m_order;
};

}  // namespace

GpuMeshLayout build_gpu_mesh_layout(const TetMesh& m) {
  require(m.neighbors.size() == m.tets.size(),
          "GpuRayCaster: mesh has " + std::to_string(m.neighbors.size()) + " neighbour entries for " +
              std::to_string(m.tets.size()) + " tets; expected a mesh from prepare_tet_mesh");
  constexpr std::size_t kMaxTets = std::size_t{1} << 29;  // a neighbour is packed as tet << 2 | face
  require(m.tets.size() < kMaxTets, "GpuRayCaster: mesh has " + std::to_string(m.tets.size()) +
                                         " tets; the GPU layout indexes at most 2^29 - 1 tets");
  require(m.points.size() < (std::size_t{1} << 31) / 3,
          "GpuRayCaster: mesh has " + std::to_string(m.points.size()) + " points; at most 715827882 fit int32 indexing");
  GpuMeshLayout g;
  const std::vector<std::int32_t> order = detail::morton_order(m);
  std::vector<std::int32_t> rank(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) rank[static_cast<std::size_t>(order[i])] = static_cast<std::int32_t>(i);
  g.tet_vertices.resize(m.tets.size());
  g.tet_next.resize(m.tets.size());
  parallel_for(order.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const auto t = static_cast<std::size_t>(order[i]);
      for (int k = 0; k < 4; ++k) {
        g.tet_vertices[i][static_cast<std::size_t>(k)] = m.tets[t][static_cast<std::size_t>(k)];
        std::int32_t next = -1;
        const std::int32_t n = m.neighbors[t][static_cast<std::size_t>(k)];
        if (n >= 0)
          for (int j = 0; j < 4; ++j)
            if (m.neighbors[static_cast<std::size_t>(n)][static_cast<std::size_t>(j)] == static_cast<std::int32_t>(t))
              next = (rank[static_cast<std::size_t>(n)] << 2) | j;
        g.tet_next[i][static_cast<std::size_t>(k)] = next;
      }
    }
  });
  g.boundary.reserve(m.boundary.size());
  for (const auto& bf : m.boundary) {
    const auto& tv = m.tets[static_cast<std::size_t>(bf.tet)];
    std::array<std::int32_t, 4> tri{};
    for (int j = 0; j < 3; ++j) tri[static_cast<std::size_t>(j)] = tv[static_cast<std::size_t>(kFaceVertices[bf.face][j])];
    tri[3] = (rank[static_cast<std::size_t>(bf.tet)] << 2) | bf.face;
    g.boundary.push_back(tri);
  }
  place_gpu_mesh_points(m, g);
  return g;
}

void place_gpu_mesh_points(const TetMesh& m, GpuMeshLayout& g) {
  g.frame = m.frame;
  g.diagonal = g.frame.length(m.bounds.diagonal());
  g.points.resize(m.points.size() * 3);
  parallel_for(m.points.size(), 1 << 15, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Vec3d p = g.frame.point(m.points[i]);
      for (int a = 0; a < 3; ++a) g.points[3 * i + static_cast<std::size_t>(a)] = static_cast<float>(p[a]);
    }
  });
  std::vector<Box> boxes(g.boundary.size());
  for (std::size_t i = 0; i < g.boundary.size(); ++i) {
    Box& box = boxes[i];
    for (int a = 0; a < 3; ++a) {
      box.lo[a] = std::numeric_limits<float>::infinity();
      box.hi[a] = -std::numeric_limits<float>::infinity();
    }
    for (int j = 0; j < 3; ++j) {
      const float* p = &g.points[3 * static_cast<std::size_t>(g.boundary[i][static_cast<std::size_t>(j)])];
      for (int a = 0; a < 3; ++a) {
        box.lo[a] = std::min(box.lo[a], p[a]);
        box.hi[a] = std::max(box.hi[a], p[a]);
      }
    }
  }
  std::vector<std::int32_t> leaf_order;
  BvhBuilder(boxes, static_cast<float>(1e-5 * std::max(g.diagonal, 1e-30)), g.nodes, leaf_order);
  g.triangles.resize(g.boundary.size());
  for (std::size_t i = 0; i < leaf_order.size(); ++i) g.triangles[i] = g.boundary[static_cast<std::size_t>(leaf_order[i])];
}

}  // namespace penumbra::render::gpu
