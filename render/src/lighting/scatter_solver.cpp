// render/src/lighting/scatter_solver.cpp -- Jacobi-preconditioned conjugate gradients for eq. 12
#include "scatter_solver.h"

#include <algorithm>
#include <cmath>

#include "penumbra/core/thread_pool.h"

namespace penumbra::render::lighting {
namespace {

// Points are cut into this many fixed blocks, processed in parallel; per-block partial sums are
// added in block order, so results do not depend on the thread count.
constexpr std::size_t kBlocks = 64;

template <class Body>
void for_blocks(std::size_t n, const Body& body) {
  const std::size_t size = (n + kBlocks - 1) / kBlocks;
  parallel_for(kBlocks, 1, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) body(b, std::min(n, b * size), std::min(n, (b + 1) * size));
  });
}

}  // namespace

ScatterSolver::ScatterSolver(const TetMesh& mesh, const Level1Topology& topology) : m_topology(&topology) {
  const std::size_t np = topology.edge_offsets.size() - 1;
  m_a.assign(topology.edge_ids.size(), 0.0f);
  m_a_sum.assign(np, 0.0);
  for_blocks(np, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      double sum = 0.0;
      for (auto s = topology.edge_offsets[v]; s < topology.edge_offsets[v + 1]; ++s) {
        const auto q = static_cast<std::size_t>(topology.edge_ids[static_cast<std::size_t>(s)]);
        const Vec3d d = mesh.points[q] - mesh.points[v];
        const double d2 = dot(d, d);
        // 1 / d^2 from the same squared length at both ends: the matrix is exactly symmetric.
        const float a = d2 > 0 ? static_cast<float>(1.0 / d2) : 0.0f;
        m_a[static_cast<std::size_t>(s)] = a;
        sum += a;
      }
      m_a_sum[v] = sum;
    }
  });
}

void ScatterSolver::start(const std::vector<float>& pre, const std::array<double, 3>& sigma_s,
                          const std::vector<float>& initial) {
  const Level1Topology& topo = *m_topology;
  const std::size_t np = m_a_sum.size();
  m_sigma = sigma_s;
  m_pre = pre;
  m_finite.resize(np);
  for (std::size_t v = 0; v < np; ++v)
    m_finite[v] = std::isfinite(pre[3 * v]) && std::isfinite(pre[3 * v + 1]) && std::isfinite(pre[3 * v + 2]);
  m_finite_sum.assign(np, 0.0);
  m_x.assign(3 * np, 0.0);
  m_r.assign(3 * np, 0.0);
  m_p.assign(3 * np, 0.0);
  m_q.assign(3 * np, 0.0);
  for (int c = 0; c < 3; ++c) m_active[static_cast<std::size_t>(c)] = sigma_s[static_cast<std::size_t>(c)] > 0.0;
  std::array<std::array<double, 3>, kBlocks> rz{};
  std::array<double, kBlocks> largest{};
  for_blocks(np, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      double sum = 0.0;
      for (auto s = topo.edge_offsets[v]; s < topo.edge_offsets[v + 1]; ++s)
        if (m_finite[static_cast<std::size_t>(topo.edge_ids[static_cast<std::size_t>(s)])]) sum += m_a[static_cast<std::size_t>(s)];
      m_finite_sum[v] = sum;
      for (int c = 0; c < 3; ++c) {
        const float x0 = initial[3 * v + c];
        m_x[3 * v + c] = m_finite[v] ? (std::isfinite(x0) && m_active[static_cast<std::size_t>(c)] ? x0 : pre[3 * v + c]) : 0.0;
      }
    }
  });
  // r = b - M x with b = A / 6 * L0; z = r / diag; p = z.
  for_blocks(np, [&](std::size_t b, std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      if (!in_system(v)) continue;
      double neighbours[3];
      neighbour_sum(v, m_x, neighbours);
      for (int c = 0; c < 3; ++c) {
        if (!m_active[static_cast<std::size_t>(c)]) continue;
        const double diag = diagonal(v, c);
        const double r = m_a_sum[v] / 6.0 * pre[3 * v + c] - (diag * m_x[3 * v + c] - m_sigma[static_cast<std::size_t>(c)] * neighbours[c]);
        const double z = r / diag;
        m_r[3 * v + c] = r;
        m_p[3 * v + c] = z;
        rz[b][static_cast<std::size_t>(c)] += r * z;
        largest[b] = std::max(largest[b], std::fabs(z));
      }
    }
  });
  m_rz = {0, 0, 0};
  m_residual = 0.0;
  for (std::size_t b = 0; b < kBlocks; ++b) {
    for (std::size_t c = 0; c < 3; ++c) m_rz[c] += rz[b][c];
    m_residual = std::max(m_residual, largest[b]);
  }
  for (std::size_t c = 0; c < 3; ++c) m_active[c] = m_active[c] && m_rz[c] > 0.0;
}

void ScatterSolver::neighbour_sum(std::size_t v, const std::vector<double>& values, double out[3]) const {
  const Level1Topology& topo = *m_topology;
  out[0] = out[1] = out[2] = 0.0;
  for (auto s = topo.edge_offsets[v]; s < topo.edge_offsets[v + 1]; ++s) {
    const auto q = static_cast<std::size_t>(topo.edge_ids[static_cast<std::size_t>(s)]);
    const double a = m_a[static_cast<std::size_t>(s)];
    out[0] += a * values[3 * q];
    out[1] += a * values[3 * q + 1];
    out[2] += a * values[3 * q + 2];
  }
}

std::array<double, 3> ScatterSolver::multiply() {
  const std::size_t np = m_a_sum.size();
  std::array<std::array<double, 3>, kBlocks> pq{};
  for_blocks(np, [&](std::size_t b, std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      if (!in_system(v)) continue;
      double neighbours[3];
      neighbour_sum(v, m_p, neighbours);
      for (int c = 0; c < 3; ++c) {
        const double q = diagonal(v, c) * m_p[3 * v + c] - m_sigma[static_cast<std::size_t>(c)] * neighbours[c];
        m_q[3 * v + c] = q;
        pq[b][static_cast<std::size_t>(c)] += m_p[3 * v + c] * q;
      }
    }
  });
  std::array<double, 3> sum{0, 0, 0};
  for (const auto& part : pq)
    for (std::size_t c = 0; c < 3; ++c) sum[c] += part[c];
  return sum;
}

double ScatterSolver::iterate() {
  if (!m_active[0] && !m_active[1] && !m_active[2]) return m_residual = 0.0;
  const std::size_t np = m_a_sum.size();
  const std::array<double, 3> pq = multiply();
  std::array<double, 3> alpha{0, 0, 0};
  for (std::size_t c = 0; c < 3; ++c) {
    if (m_active[c] && !(pq[c] > 0.0)) m_active[c] = false;  // converged to rounding
    if (m_active[c]) alpha[c] = m_rz[c] / pq[c];
  }
  // x += alpha p, r -= alpha q, z = r / diag (kept in q).
  std::array<std::array<double, 3>, kBlocks> rz{};
  std::array<double, kBlocks> largest{};
  for_blocks(np, [&](std::size_t b, std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      if (!in_system(v)) continue;
      for (int c = 0; c < 3; ++c) {
        if (!m_active[static_cast<std::size_t>(c)]) continue;
        const std::size_t i = 3 * v + c;
        m_x[i] += alpha[static_cast<std::size_t>(c)] * m_p[i];
        m_r[i] -= alpha[static_cast<std::size_t>(c)] * m_q[i];
        const double z = m_r[i] / diagonal(v, c);
        m_q[i] = z;
        rz[b][static_cast<std::size_t>(c)] += m_r[i] * z;
        largest[b] = std::max(largest[b], std::fabs(z));
      }
    }
  });
  std::array<double, 3> rz_new{0, 0, 0}, beta{0, 0, 0};
  m_residual = 0.0;
  for (std::size_t b = 0; b < kBlocks; ++b) {
    for (std::size_t c = 0; c < 3; ++c) rz_new[c] += rz[b][c];
    m_residual = std::max(m_residual, largest[b]);
  }
  for (std::size_t c = 0; c < 3; ++c) {
    if (!m_active[c]) continue;
    beta[c] = rz_new[c] / m_rz[c];
    m_rz[c] = rz_new[c];
    if (!(rz_new[c] > 0.0)) m_active[c] = false;
  }
  // p = z + beta p.
  for_blocks(np, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      if (!in_system(v)) continue;
      for (int c = 0; c < 3; ++c)
        if (m_active[static_cast<std::size_t>(c)]) m_p[3 * v + c] = m_q[3 * v + c] + beta[static_cast<std::size_t>(c)] * m_p[3 * v + c];
    }
  });
  return m_residual;
}

void ScatterSolver::read(std::vector<float>& rgb) const {
  const Level1Topology& topo = *m_topology;
  const std::size_t np = m_a_sum.size();
  rgb.resize(3 * np);
  for_blocks(np, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      if (m_finite[v]) {
        for (int c = 0; c < 3; ++c)
          rgb[3 * v + c] = in_system(v) ? static_cast<float>(m_x[3 * v + c]) : m_pre[3 * v + c];
        continue;
      }
      // No source here: the weighted mean of the finite neighbours.
      double sum[3] = {0, 0, 0}, weight = 0.0;
      for (auto s = topo.edge_offsets[v]; s < topo.edge_offsets[v + 1]; ++s) {
        const auto q = static_cast<std::size_t>(topo.edge_ids[static_cast<std::size_t>(s)]);
        if (!m_finite[q]) continue;
        const double a = m_a[static_cast<std::size_t>(s)];
        for (int c = 0; c < 3; ++c) sum[c] += a * (in_system(q) ? m_x[3 * q + c] : m_pre[3 * q + c]);
        weight += a;
      }
      for (int c = 0; c < 3; ++c) rgb[3 * v + c] = weight > 0 ? static_cast<float>(sum[c] / weight) : 0.0f;
    }
  });
}

}  // namespace penumbra::render::lighting
