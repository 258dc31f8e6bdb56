// SPDX-License-Identifier: BSD-3-Clause
// render/src/walk_mesh.cpp -- walk records from a prepared mesh
#include "walk_mesh.h"

#include "penumbra/core/thread_pool.h"

namespace penumbra::render::detail {

std::vector<WalkTet> walk_tets(const TetMesh& mesh, const std::vector<std::int32_t>& order) {
  std::vector<std::int32_t> rank(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) rank[static_cast<std::size_t>(order[i])] = static_cast<std::int32_t>(i);
  std::vector<WalkTet> tets(order.size());
  parallel_for(tets.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const auto t = static_cast<std::size_t>(order[i]);
      for (int k = 0; k < 4; ++k) {
        tets[i].v[k] = mesh.tets[t][k];
        const std::int32_t n = mesh.neighbors[t][k];
        tets[i].next[k] = -1;
        if (n < 0) continue;
        // The shared face's index in the neighbour: the face whose neighbour is t.
        for (int j = 0; j < 4; ++j)
          if (mesh.neighbors[static_cast<std::size_t>(n)][j] == static_cast<std::int32_t>(t))
            tets[i].next[k] = (rank[static_cast<std::size_t>(n)] << 2) | j;
      }
    }
  });
  return tets;
}

}  // namespace penumbra::render::detail
