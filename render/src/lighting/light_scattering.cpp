// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/light_scattering.cpp -- Chebyshev-accelerated Jacobi diffusion of the light colour field
#include "light_scattering.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "penumbra/core/thread_pool.h"
#include "tet_order.h"

namespace penumbra::render::lighting {

std::vector<float> scatter_weights(const TetMesh& mesh, const Level1Topology& topology) {
  std::vector<float> w(topology.edge_ids.size(), 0.0f);
  parallel_for(mesh.points.size(), 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p) {
      const auto s0 = topology.edge_offsets[p], s1 = topology.edge_offsets[p + 1];
      double inv_sum = 0;
      for (auto s = s0; s < s1; ++s) {
        const auto q = static_cast<std::size_t>(topology.edge_ids[static_cast<std::size_t>(s)]);
        // In the mesh's frame (a power-of-two scale: the weights do not change), so that 1 / d^2
        // fits float32 for a mesh of any size.
        const Vec3d dv = (mesh.points[q] - mesh.points[p]) / mesh.frame.scale;
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

ScatterPlan plan_scatter(const TetMesh& mesh, const Level1Topology& topology, const std::vector<float>& weights) {
  constexpr std::size_t C = kScatterSlice;
  ScatterPlan plan;
  const std::size_t np = topology.edge_offsets.size() - 1;
  auto degree = [&](std::int32_t p) {
    return topology.edge_offsets[static_cast<std::size_t>(p) + 1] - topology.edge_offsets[static_cast<std::size_t>(p)];
  };
  plan.order = detail::morton_point_order(mesh);
  for (std::size_t b = 0; b < np; b += ScatterPlan::kDegreeWindow)
    std::stable_sort(plan.order.begin() + static_cast<std::ptrdiff_t>(b),
                     plan.order.begin() + static_cast<std::ptrdiff_t>(std::min(np, b + ScatterPlan::kDegreeWindow)),
                     [&](std::int32_t a, std::int32_t c) { return degree(a) > degree(c); });
  std::vector<std::int32_t> position(np);
  for (std::size_t k = 0; k < np; ++k) position[static_cast<std::size_t>(plan.order[k])] = static_cast<std::int32_t>(k);
  const std::size_t chunk = (np + kScatterChunks * C - 1) / (kScatterChunks * C) * C;
  plan.chunk_begin.resize(kScatterChunks + 1);
  for (std::size_t c = 0; c <= kScatterChunks; ++c) plan.chunk_begin[c] = std::min(np, c * chunk);
  const std::size_t slices = (np + C - 1) / C;
  plan.slice_begin.assign(slices + 1, 0);
  for (std::size_t s = 0; s < slices; ++s) {
    std::int64_t columns = 0;
    for (std::size_t k = s * C; k < std::min(np, (s + 1) * C); ++k) columns = std::max(columns, degree(plan.order[k]));
    plan.slice_begin[s + 1] = plan.slice_begin[s] + columns * static_cast<std::int64_t>(C);
  }
  const auto entries = static_cast<std::size_t>(plan.slice_begin[slices]);
  plan.ids.resize(entries);
  plan.weights.resize(entries);
  plan.weight_sums.assign(np, 0.0f);
  parallel_for(slices, 256, [&](std::size_t b, std::size_t e) {
    for (std::size_t s = b; s < e; ++s) {
      const auto first = static_cast<std::size_t>(plan.slice_begin[s]);
      const std::size_t columns = (static_cast<std::size_t>(plan.slice_begin[s + 1]) - first) / C;
      for (std::size_t i = 0; i < C; ++i) {
        const std::size_t k = s * C + i;
        // Padding reads a value that exists and is finite: the position's own, or position 0
        // past the last point.
        const std::int32_t own = k < np ? static_cast<std::int32_t>(k) : 0;
        const std::size_t p = k < np ? static_cast<std::size_t>(plan.order[k]) : 0;
        const auto e0 = k < np ? static_cast<std::size_t>(topology.edge_offsets[p]) : 0;
        const auto n = k < np ? static_cast<std::size_t>(topology.edge_offsets[p + 1]) - e0 : 0;
        for (std::size_t col = 0; col < columns; ++col) {
          const std::size_t at = first + col * C + i;
          plan.ids[at] = col < n ? position[static_cast<std::size_t>(topology.edge_ids[e0 + col])] : own;
          plan.weights[at] = col < n ? weights[e0 + col] : 0.0f;
          if (k < np) plan.weight_sums[k] += plan.weights[at];
        }
      }
    }
  });
  return plan;
}

void to_plan_order(const ScatterPlan& plan, const std::vector<float>& by_point, std::vector<float>& by_position) {
  by_position.resize(kPlannedStride * plan.order.size());
  parallel_for(plan.order.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      const auto p = static_cast<std::size_t>(plan.order[k]);
      for (int c = 0; c < 3; ++c) by_position[kPlannedStride * k + c] = by_point[3 * p + c];
      by_position[kPlannedStride * k + 3] = 0.0f;
    }
  });
}

void to_point_order(const ScatterPlan& plan, const std::vector<float>& by_position, std::vector<float>& by_point) {
  by_point.resize(3 * plan.order.size());
  parallel_for(plan.order.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      const auto p = static_cast<std::size_t>(plan.order[k]);
      for (int c = 0; c < 3; ++c) by_point[3 * p + c] = by_position[kPlannedStride * k + c];
    }
  });
}

void chebyshev_weights(int k, const std::array<double, 3>& sigma_s, std::array<double, 3>& omega) {
  for (std::size_t ch = 0; ch < 3; ++ch) {
    const double rho = 6.0 * sigma_s[ch] / (1.0 + 6.0 * sigma_s[ch]);
    double& w = omega[ch];
    w = k == 0 ? 1.0 : k == 1 ? 1.0 / (1.0 - 0.5 * rho * rho) : 1.0 / (1.0 - 0.25 * rho * rho * w);
  }
}

double scatter_iteration(const ScatterPlan& plan, const std::vector<float>& pre, const std::array<double, 3>& sigma_s,
                         std::vector<float>& current, ScatterSolve& solve) {
  scatter_iteration_part(plan, pre, sigma_s, current, solve, kScatterChunks);
  return solve.residual;
}

void scatter_prepare(const ScatterPlan& plan, const std::vector<float>& pre, std::vector<float>& current,
                     ScatterSolve& solve) {
  constexpr std::size_t S = kPlannedStride;
  const std::size_t np = plan.order.size();
  // Which points have a finite source, once per solve. Points without one are left out of
  // every sum by a masked copy of the weights, made only when there are any, so that the
  // inner loop has no test.
  solve.finite.resize(np);
  std::vector<std::uint8_t> any(kScatterChunks, 0);
  parallel_for(kScatterChunks, 1, [&](std::size_t c0, std::size_t c1) {
    for (std::size_t c = c0; c < c1; ++c) {
      bool some = false;  // a local: the threads' entries of `any` share a cache line
      for (std::size_t p = plan.chunk_begin[c]; p < plan.chunk_begin[c + 1]; ++p) {
        solve.finite[p] = std::isfinite(pre[S * p] + pre[S * p + 1] + pre[S * p + 2]);
        some = some || !solve.finite[p];
        // A weight of 0 does not remove a NaN (0 * NaN is NaN): a start value that is not
        // finite is replaced by the source, or 0 where that is not finite either.
        for (std::size_t ch = 0; ch < 3; ++ch)
          if (!std::isfinite(current[S * p + ch])) current[S * p + ch] = solve.finite[p] ? pre[S * p + ch] : 0.0f;
      }
      any[c] = some;
    }
  });
  solve.masked = std::find(any.begin(), any.end(), 1) != any.end();
  if (solve.masked) {
    constexpr std::size_t C = kScatterSlice;
    solve.masked_weights = plan.weights;
    solve.masked_sums.assign(np, 0.0f);
    parallel_for(plan.slices(), 256, [&](std::size_t b, std::size_t e) {
      for (std::size_t s = b; s < e; ++s)
        for (auto at = static_cast<std::size_t>(plan.slice_begin[s]); at < static_cast<std::size_t>(plan.slice_begin[s + 1]);
             ++at) {
          float& w = solve.masked_weights[at];
          if (!solve.finite[static_cast<std::size_t>(plan.ids[at])]) w = 0.0f;
          const std::size_t k = s * C + at % C;
          if (k < np) solve.masked_sums[k] += w;
        }
    });
  } else {
    solve.masked_weights = {};
    solve.masked_sums = {};
  }
  solve.other.resize(current.size());
  solve.prepared = true;
}

bool scatter_iteration_part(const ScatterPlan& plan, const std::vector<float>& pre, const std::array<double, 3>& sigma_s,
                            std::vector<float>& current, ScatterSolve& solve, std::size_t chunks) {
  // Four channels (the fourth is padding) in one vector: a neighbour costs one load and one
  // multiply-add. Sums in float: a dozen positive terms, relative error ~1e-7.
  typedef float Colour __attribute__((vector_size(16)));
  constexpr std::size_t S = kPlannedStride;
  if (!solve.prepared) scatter_prepare(plan, pre, current, solve);
  if (solve.next_chunk == 0) {
    chebyshev_weights(solve.iterations, sigma_s, solve.omega);
    solve.residual = 0.0;
  }
  const std::size_t first = solve.next_chunk;
  const std::size_t last = std::min(kScatterChunks, first + std::max<std::size_t>(chunks, 1));
  const std::vector<std::uint8_t>& finite = solve.finite;
  const float* weights = solve.masked ? solve.masked_weights.data() : plan.weights.data();
  const float* sums_of = solve.masked ? solve.masked_sums.data() : plan.weight_sums.data();
  const bool plain = solve.iterations == 0;  // L_1 = J(L_0): L_{-1} does not exist
  const Colour omega = {static_cast<float>(solve.omega[0]), static_cast<float>(solve.omega[1]),
                        static_cast<float>(solve.omega[2]), 0.0f};
  const Colour s = {static_cast<float>(sigma_s[0]), static_cast<float>(sigma_s[1]), static_cast<float>(sigma_s[2]), 0.0f};
  const Colour one = {1, 1, 1, 1};
  std::vector<double> residuals(last - first, 0.0);
  constexpr std::size_t C = kScatterSlice;
  parallel_for(last - first, 1, [&](std::size_t c0, std::size_t c1) {
    for (std::size_t c = first + c0; c < first + c1; ++c) {
      const std::size_t begin = plan.chunk_begin[c], end = plan.chunk_begin[c + 1];
      // Blocks past the last point are empty. (Their begin, the point count, need not be a
      // multiple of a slice: the loop below would then redo the last slice, reading as L_{k-1}
      // what its own block had already overwritten with L_{k+1}, at the same time.)
      if (begin == end) continue;
      float residual = 0.0f;
      for (std::size_t slice = begin / C; slice * C < end; ++slice) {
        // The slice's neighbour sums, a column at a time.
        Colour sums[C];
        for (Colour& sum : sums) sum = Colour{0, 0, 0, 0};
        const auto entry_end = static_cast<std::size_t>(plan.slice_begin[slice + 1]);
        for (auto at = static_cast<std::size_t>(plan.slice_begin[slice]); at < entry_end; at += C)
          for (std::size_t i = 0; i < C; ++i) {
            Colour v;
            std::memcpy(&v, current.data() + S * static_cast<std::size_t>(plan.ids[at + i]), sizeof v);
            sums[i] += weights[at + i] * v;
          }
        for (std::size_t p = slice * C; p < std::min(end, (slice + 1) * C); ++p) {
          const Colour sum = sums[p - slice * C];
          const float wsum = sums_of[p];
          Colour jacobi, next;
          if (finite[p]) {
            // (L0 + s sum w L) / (1 + s sum w); with s = 0 or no neighbours the source itself.
            Colour source;
            std::memcpy(&source, pre.data() + S * p, sizeof source);
            jacobi = (source + s * sum) / (one + s * wsum);
            next = jacobi;
            if (!plain) {
              Colour before;
              std::memcpy(&before, solve.other.data() + S * p, sizeof before);
              next = before + omega * (jacobi - before);
            }
          } else {
            // No source of its own: the weighted mean of its finite neighbours (0 without any).
            next = wsum > 0 ? sum / wsum : Colour{0, 0, 0, 0};
          }
          next[3] = 0.0f;
          Colour now;
          std::memcpy(&now, current.data() + S * p, sizeof now);
          const Colour diff = next - now;
          for (int ch = 0; ch < 3; ++ch) {
            const float change = std::fabs(diff[ch]);
            if (change > residual && change <= HUGE_VALF) residual = change;
          }
          std::memcpy(solve.other.data() + S * p, &next, sizeof next);
        }
      }
      residuals[c - first] = residual;
    }
  });
  for (double r : residuals) solve.residual = std::max(solve.residual, r);
  solve.next_chunk = last == kScatterChunks ? 0 : last;
  if (solve.next_chunk != 0) return false;
  current.swap(solve.other);
  ++solve.iterations;
  return true;
}

}  // namespace penumbra::render::lighting
