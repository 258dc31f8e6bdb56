// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level1_mesh.cpp -- point-to-tet and point-to-point adjacency, the walk records
#include "level1_mesh.h"

#include <algorithm>
#include <cmath>

#include "penumbra/core/thread_pool.h"
#include "tet_geometry.h"
#include "tet_order.h"

namespace penumbra::render::lighting {

Level1Topology::Level1Topology(const TetMesh& mesh) {
  const std::size_t np = mesh.points.size(), nt = mesh.tets.size();
  tet_offsets.assign(np + 1, 0);
  for (const auto& tv : mesh.tets)
    for (int k = 0; k < 4; ++k) ++tet_offsets[static_cast<std::size_t>(tv[k]) + 1];
  for (std::size_t p = 0; p < np; ++p) tet_offsets[p + 1] += tet_offsets[p];
  // The tets around each point (and the point's local index in each), for the stencil and the
  // star below.
  std::vector<std::int32_t> tet_ids(static_cast<std::size_t>(tet_offsets[np]));
  std::vector<std::int8_t> tet_local(tet_ids.size());
  std::vector<std::int64_t> fill(tet_offsets.begin(), tet_offsets.end() - 1);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k) {
      const auto slot = static_cast<std::size_t>(fill[static_cast<std::size_t>(mesh.tets[t][k])]++);
      tet_ids[slot] = static_cast<std::int32_t>(t);
      tet_local[slot] = static_cast<std::int8_t>(k);
    }

  // Edge neighbours: the other three vertices of each incident tet, deduplicated per point.
  edge_offsets.assign(np + 1, 0);
  std::vector<std::vector<std::int32_t>> chunks(np);
  std::vector<std::int64_t> counts(np, 0);
  parallel_for(np, 1024, [&](std::size_t b, std::size_t e) {
    std::vector<std::int32_t> tmp;
    for (std::size_t p = b; p < e; ++p) {
      tmp.clear();
      for (auto s = tet_offsets[p]; s < tet_offsets[p + 1]; ++s) {
        const auto& tv = mesh.tets[static_cast<std::size_t>(tet_ids[static_cast<std::size_t>(s)])];
        for (int k = 0; k < 4; ++k)
          if (static_cast<std::size_t>(tv[k]) != p) tmp.push_back(tv[k]);
      }
      std::sort(tmp.begin(), tmp.end());
      tmp.erase(std::unique(tmp.begin(), tmp.end()), tmp.end());
      chunks[p] = tmp;
      counts[p] = static_cast<std::int64_t>(tmp.size());
    }
  });
  for (std::size_t p = 0; p < np; ++p) edge_offsets[p + 1] = edge_offsets[p] + counts[p];
  edge_ids.resize(static_cast<std::size_t>(edge_offsets[np]));
  for (std::size_t p = 0; p < np; ++p) std::copy(chunks[p].begin(), chunks[p].end(), edge_ids.begin() + edge_offsets[p]);
  measure_edges(mesh);
  const std::vector<std::int32_t> order = detail::morton_order(mesh);
  std::vector<std::int32_t> record_of(nt);  // tet id -> its walk record
  for (std::size_t i = 0; i < order.size(); ++i) record_of[static_cast<std::size_t>(order[i])] = static_cast<std::int32_t>(i);
  walk_tets = detail::walk_tets(mesh, order);
  star.resize(tet_ids.size());
  parallel_for(star.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t s = b; s < e; ++s) {
      const auto t = static_cast<std::size_t>(tet_ids[s]);
      const int k = tet_local[s];
      star[s].record = record_of[t] << 2 | k;
      for (int j = 0; j < 3; ++j) star[s].v[j] = mesh.tets[t][detail::kFaceVertices[k][j]];
    }
  });
}

void Level1Topology::measure_edges(const TetMesh& mesh) {
  const std::size_t np = mesh.points.size();
  double sum = 0, smallest = HUGE_VAL;
  std::size_t edges = 0;
  longest_edge.assign(np, 0.0f);
  for (std::size_t p = 0; p < np; ++p)
    for (auto e = edge_offsets[p]; e < edge_offsets[p + 1]; ++e) {
      const auto q = static_cast<std::size_t>(edge_ids[static_cast<std::size_t>(e)]);
      const double d = length(mesh.points[q] - mesh.points[p]);
      longest_edge[p] = std::max(longest_edge[p], static_cast<float>(d));
      if (q < p) continue;  // each edge once
      if (!(d > 0)) continue;
      sum += d;
      smallest = std::min(smallest, d);
      ++edges;
    }
  mean_edge = edges ? sum / static_cast<double>(edges) : 0.0;
  min_edge = edges ? smallest : 0.0;
}

void Level1Field::build(const std::vector<float>& point_scalars, const TransferFunction& tf) {
  table = ExtinctionTable(tf);
  scalars = point_scalars;
}

}  // namespace penumbra::render::lighting
