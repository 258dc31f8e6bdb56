// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/rank_scattering.cpp -- Jacobi iterations of the scattering with the ranks' boundary sums exchanged
#include "rank_scattering.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

#include "penumbra/core/thread_pool.h"

namespace penumbra::insitu {
namespace {

using Edge = std::pair<std::int32_t, std::int32_t>;

// The mesh's edges, each once (smaller id first).
std::vector<Edge> unique_edges(const render::TetMesh& mesh) {
  std::vector<Edge> edges;
  edges.reserve(6 * mesh.tets.size());
  for (const auto& t : mesh.tets)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) edges.emplace_back(std::min(t[a], t[b]), std::max(t[a], t[b]));
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

// Per peer, this rank's edges between two points it shares with that peer, as pairs of their
// places in the pair's common list: what the peer compares with its own edges.
std::vector<std::vector<double>> shared_edge_messages(const RankGroup& group, const SharedPoints& shared,
                                                      const std::vector<std::int32_t>& slot_of, const std::vector<Edge>& edges,
                                                      std::vector<std::vector<std::int32_t>>& place) {
  const auto& peers = shared.peer_list();
  place.assign(peers.size(), std::vector<std::int32_t>(shared.size(), -1));
  for (std::size_t q = 0; q < peers.size(); ++q)
    for (std::size_t j = 0; j < peers[q].slots.size(); ++j) place[q][peers[q].slots[j]] = static_cast<std::int32_t>(j);
  std::vector<std::vector<double>> to_each(static_cast<std::size_t>(group.size()));
  for (const Edge& e : edges) {
    const std::int32_t sa = slot_of[static_cast<std::size_t>(e.first)], sb = slot_of[static_cast<std::size_t>(e.second)];
    if (sa < 0 || sb < 0) continue;
    for (std::size_t q = 0; q < peers.size(); ++q) {
      const std::int32_t ja = place[q][static_cast<std::size_t>(sa)], jb = place[q][static_cast<std::size_t>(sb)];
      if (ja >= 0 && jb >= 0)
        to_each[static_cast<std::size_t>(peers[q].rank)].insert(to_each[static_cast<std::size_t>(peers[q].rank)].end(),
                                                                 {double(std::min(ja, jb)), double(std::max(ja, jb))});
    }
  }
  return to_each;
}

}  // namespace

RankScattering::RankScattering(RankGroup& group, const render::TetMesh& mesh, const SharedPoints& shared)
    : m_shared(shared), m_slot_of(mesh.points.size(), -1) {
  for (std::size_t s = 0; s < shared.points().size(); ++s) m_slot_of[static_cast<std::size_t>(shared.points()[s])] = static_cast<std::int32_t>(s);
  const std::vector<Edge> edges = unique_edges(mesh);
  // An edge between shared points that a lower rank also has is that rank's to count.
  std::vector<std::vector<std::int32_t>> place;
  const auto received = group.exchange(shared_edge_messages(group, shared, m_slot_of, edges, place));
  std::vector<std::set<std::pair<std::int32_t, std::int32_t>>> lower_has(shared.peer_list().size());
  for (std::size_t q = 0; q < shared.peer_list().size(); ++q) {
    const int r = shared.peer_list()[q].rank;
    if (r > group.rank()) continue;
    const std::vector<double>& got = received[static_cast<std::size_t>(r)];
    for (std::size_t i = 0; i + 1 < got.size(); i += 2)
      lower_has[q].insert({static_cast<std::int32_t>(got[i]), static_cast<std::int32_t>(got[i + 1])});
  }
  auto counted_here = [&](const Edge& e) {
    const std::int32_t sa = m_slot_of[static_cast<std::size_t>(e.first)], sb = m_slot_of[static_cast<std::size_t>(e.second)];
    if (sa < 0 || sb < 0) return true;
    for (std::size_t q = 0; q < place.size(); ++q) {
      const std::int32_t ja = place[q][static_cast<std::size_t>(sa)], jb = place[q][static_cast<std::size_t>(sb)];
      if (ja >= 0 && jb >= 0 && lower_has[q].count({std::min(ja, jb), std::max(ja, jb)})) return false;
    }
    return true;
  };
  // Counted edges, both ways, as adjacency lists with 1 / d^2 in the common frame.
  const std::size_t np = mesh.points.size();
  std::vector<std::int64_t> degree(np + 1, 0);
  std::vector<Edge> kept;
  for (const Edge& e : edges)
    if (counted_here(e)) {
      kept.push_back(e);
      ++degree[static_cast<std::size_t>(e.first)];
      ++degree[static_cast<std::size_t>(e.second)];
    }
  m_offsets.assign(np + 1, 0);
  for (std::size_t p = 0; p < np; ++p) m_offsets[p + 1] = m_offsets[p] + degree[p];
  m_neighbours.resize(static_cast<std::size_t>(m_offsets[np]));
  m_inverse_square.resize(m_neighbours.size());
  std::vector<std::int64_t> at(m_offsets.begin(), m_offsets.end() - 1);
  for (const Edge& e : kept) {
    const Vec3d d = (mesh.points[static_cast<std::size_t>(e.second)] - mesh.points[static_cast<std::size_t>(e.first)]) / mesh.frame.scale;
    const double d2 = dot(d, d), inv = d2 > 0 ? 1.0 / d2 : 0.0;
    for (const auto& [from, to] : {e, Edge{e.second, e.first}}) {
      const auto i = static_cast<std::size_t>(at[static_cast<std::size_t>(from)]++);
      m_neighbours[i] = to;
      m_inverse_square[i] = inv;
    }
  }
  m_inverse_sum.assign(np, 0.0);
  for (std::size_t p = 0; p < np; ++p)
    for (auto i = m_offsets[p]; i < m_offsets[p + 1]; ++i) m_inverse_sum[p] += m_inverse_square[static_cast<std::size_t>(i)];
  std::vector<double> by_slot(shared.size());
  for (std::size_t s = 0; s < shared.size(); ++s) by_slot[s] = m_inverse_sum[static_cast<std::size_t>(shared.points()[s])];
  const std::vector<double> total = shared.sum_over_holders(group, by_slot, 1);
  for (std::size_t s = 0; s < shared.size(); ++s) m_inverse_sum[static_cast<std::size_t>(shared.points()[s])] = total[s];
}

void RankScattering::jacobi(RankGroup& group, const std::vector<float>& source, const std::array<double, 3>& sigma_s,
                            const std::vector<double>& current, std::vector<double>& next) const {
  const std::size_t np = m_inverse_sum.size();
  // Each point's sum of (1 / d^2) L over its edges here; a shared point's over every rank's.
  std::vector<double> sums(3 * np, 0.0);
  parallel_for(np, 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p)
      for (auto i = m_offsets[p]; i < m_offsets[p + 1]; ++i) {
        const auto q = static_cast<std::size_t>(m_neighbours[static_cast<std::size_t>(i)]);
        for (std::size_t c = 0; c < 3; ++c) sums[3 * p + c] += m_inverse_square[static_cast<std::size_t>(i)] * current[3 * q + c];
      }
  });
  const auto& shared = m_shared.points();
  std::vector<double> by_slot(3 * shared.size());
  for (std::size_t s = 0; s < shared.size(); ++s)
    for (std::size_t c = 0; c < 3; ++c) by_slot[3 * s + c] = sums[3 * static_cast<std::size_t>(shared[s]) + c];
  const std::vector<double> total = m_shared.sum_over_holders(group, by_slot, 3);
  for (std::size_t s = 0; s < shared.size(); ++s)
    for (std::size_t c = 0; c < 3; ++c) sums[3 * static_cast<std::size_t>(shared[s]) + c] = total[3 * s + c];
  // J(L)_p = (L0_p + s sum_i w_i L_i) / (1 + s sum_i w_i), w_i = 6 (1 / d_i^2) / sum_j (1 / d_j^2).
  parallel_for(np, 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p)
      for (std::size_t c = 0; c < 3; ++c) {
        const double l0 = source[3 * p + c];
        next[3 * p + c] = m_inverse_sum[p] > 0
                              ? (l0 + sigma_s[c] * 6.0 * sums[3 * p + c] / m_inverse_sum[p]) / (1.0 + 6.0 * sigma_s[c])
                              : l0;
      }
  });
}

RankScattering::Report RankScattering::solve(RankGroup& group, const std::vector<float>& source,
                                             const std::array<double, 3>& sigma_s, double tolerance, int max_iterations,
                                             std::vector<float>& light) const {
  const std::size_t n = source.size();
  if (light.size() != n) light = source;
  double scale = 0;
  for (float v : source) scale = std::max(scale, std::fabs(static_cast<double>(v)));
  double negated = -scale;  // the largest |source| over the ranks: max(x) = -min(-x)
  group.minimum(&negated, 1);
  // Float iterates settle within a few units in the last place (light_scattering.h).
  const double stop = std::max(tolerance, 16.0 / (1 << 24)) * -negated;
  std::vector<double> previous(light.begin(), light.end()), current = previous, jacobi_of(n), next(n);
  std::array<double, 3> omega{1, 1, 1};
  Report report;
  while (report.iterations < max_iterations) {
    // Chebyshev's weights (Golub & Varga), as one process's solve uses them.
    for (std::size_t c = 0; c < 3; ++c) {
      const double rho = 6.0 * sigma_s[c] / (1.0 + 6.0 * sigma_s[c]);
      const int k = report.iterations;
      omega[c] = k == 0 ? 1.0 : k == 1 ? 1.0 / (1.0 - 0.5 * rho * rho) : 1.0 / (1.0 - 0.25 * rho * rho * omega[c]);
    }
    jacobi(group, source, sigma_s, current, jacobi_of);
    double change = 0;
    for (std::size_t i = 0; i < n; ++i) {
      next[i] = previous[i] + omega[i % 3] * (jacobi_of[i] - previous[i]);
      change = std::max(change, std::fabs(next[i] - current[i]));
    }
    previous.swap(current);
    current.swap(next);
    ++report.iterations;
    double negated_change = -change;
    group.minimum(&negated_change, 1);
    report.residual = -negated_change;
    if (report.residual <= stop) {
      report.converged = true;
      break;
    }
  }
  for (std::size_t i = 0; i < n; ++i) light[i] = static_cast<float>(current[i]);
  return report;
}

}  // namespace penumbra::insitu
