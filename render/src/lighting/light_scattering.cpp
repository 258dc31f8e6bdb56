// render/src/lighting/light_scattering.cpp -- Gauss-Seidel diffusion of the light colour field
#include "light_scattering.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

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

double scatter_sweep(const Level1Topology& topology, const std::vector<float>& weights, const std::vector<float>& pre,
                     const std::array<double, 3>& sigma_s, std::vector<float>& current, std::vector<float>& snapshot) {
  const std::size_t np = topology.edge_offsets.size() - 1;
  snapshot = current;
  // Which points have a finite source, once per sweep: the inner loop then reads one byte per
  // neighbour (a table that stays in cache) instead of gathering its three source values.
  std::vector<std::uint8_t> finite(np);
  parallel_for(np, 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p) finite[p] = std::isfinite(pre[3 * p] + pre[3 * p + 1] + pre[3 * p + 2]);
  });
  const std::size_t chunk = (np + kScatterChunks - 1) / kScatterChunks;
  std::vector<double> residuals(kScatterChunks, 0.0);
  parallel_for(kScatterChunks, 1, [&](std::size_t c0, std::size_t c1) {
    for (std::size_t c = c0; c < c1; ++c) {
      const std::size_t begin = c * chunk, end = std::min(np, begin + chunk);
      double residual = 0.0;
      for (std::size_t p = begin; p < end; ++p) {
        double sum[3] = {0, 0, 0}, wsum = 0;
        for (auto s = topology.edge_offsets[p]; s < topology.edge_offsets[p + 1]; ++s) {
          const auto q = static_cast<std::size_t>(topology.edge_ids[static_cast<std::size_t>(s)]);
          const double w = weights[static_cast<std::size_t>(s)];
          // Gauss-Seidel inside the chunk, the previous iterate across chunks.
          const float* src = (q >= begin && q < end ? current.data() : snapshot.data()) + 3 * q;
          // Points without a finite source value are left out (their own value is derived).
          if (w == 0.0 || !finite[q]) continue;
          sum[0] += w * static_cast<double>(src[0]);
          sum[1] += w * static_cast<double>(src[1]);
          sum[2] += w * static_cast<double>(src[2]);
          wsum += w;
        }
        const bool own = finite[p];
        for (int ch = 0; ch < 3; ++ch) {
          const double old = current[3 * p + ch];
          double v;
          if (!own)
            v = wsum > 0 ? sum[ch] / wsum : 0.0;
          else if (sigma_s[ch] == 0.0 || wsum == 0.0)
            v = pre[3 * p + ch];
          else
            v = (pre[3 * p + ch] + sigma_s[ch] * sum[ch]) / (1.0 + sigma_s[ch] * wsum);
          const float f = static_cast<float>(v);
          const double change = std::fabs(static_cast<double>(f) - old);
          if (std::isfinite(change)) residual = std::max(residual, change);
          current[3 * p + ch] = f;
        }
      }
      residuals[c] = residual;
    }
  });
  return *std::max_element(residuals.begin(), residuals.end());
}

}  // namespace penumbra::render::lighting
