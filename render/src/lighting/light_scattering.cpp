// render/src/lighting/light_scattering.cpp -- the diffusion weights of the light colour field
#include "light_scattering.h"

#include <algorithm>
#include <cmath>

#include "penumbra/core/thread_pool.h"

namespace penumbra::render::lighting {

std::vector<float> scatter_weights(const TetMesh& mesh, const Level1Topology& topology) {
  std::vector<float> w(topology.edge_ids.size(), 0.0f);
  parallel_for(mesh.points.size(), 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p) {
      const auto s0 = topology.edge_offsets[p], s1 = topology.edge_offsets[p + 1];
      double inv_sum = 0;
      for (auto s = s0; s < s1; ++s) {
        const auto q = static_cast<std::size_t>(topology.edge_ids[static_cast<std::size_t>(s)]);
        const Vec3d dv = mesh.points[q] - mesh.points[p];
        const double d2 = dot(dv, dv);
        const double inv = d2 > 0 ? 1.0 / d2 : 0.0;
        w[static_cast<std::size_t>(s)] = static_cast<float>(inv);
        inv_sum += inv;
      }
      if (!(inv_sum > 0)) continue;
      for (auto s = s0; s < s1; ++s) w[static_cast<std::size_t>(s)] = static_cast<float>(6.0 * w[static_cast<std::size_t>(s)] / inv_sum);
    }
  });
  return w;
}

}  // namespace penumbra::render::lighting
