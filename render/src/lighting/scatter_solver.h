// render/src/lighting/scatter_solver.h -- the implicit diffusion step (eq. 12) by conjugate gradients
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "level1_mesh.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::render::lighting {

/// Solves the backward-Euler diffusion step of light_volume.h for each channel c,
///     L_v - s_c sum_i w_vi (L_i - L_v) = L0_v,   w_vi = 6 a_vi / A_v,  a_vi = 1 / d_vi^2,  A_v = sum_i a_vi,
/// by Jacobi-preconditioned conjugate gradients.
/// Row v times A_v / 6 makes the matrix symmetric, a_vi being symmetric, and positive definite
/// (strictly diagonally dominant), so CG applies: its iteration count grows with sqrt(1 + 12 s)
/// where Gauss-Seidel's grows with 1 + 12 s, and each iteration is one pass over the edges plus
/// vector updates, in parallel over fixed blocks (the reductions are summed in block order, so
/// the result does not depend on the thread count).
/// Points whose L0 is not finite are left out of the system and of every neighbour sum, and take
/// the weighted mean of their finite neighbours (0 without any), so NaN never spreads; points
/// in no edge keep L0. The converged field is within the range of L0 and a constant stays
/// constant (the discrete maximum principle of the M-matrix); intermediate iterates may stray by
/// about the residual.
class ScatterSolver {
public:
  ScatterSolver(const TetMesh& mesh, const Level1Topology& topology);
  ScatterSolver() = default;

  /// Starts a solve for source `pre` (3 floats per point) from the estimate `initial` (3 per
  /// point; non-finite entries start from pre).
  void start(const std::vector<float>& pre, const std::array<double, 3>& sigma_s, const std::vector<float>& initial);
  /// One iteration. Returns the residual in the units of L: the largest change one Jacobi step
  /// would make, max over points and channels of |r_v / M_vv|. 0 when solved exactly.
  double iterate();
  /// The residual of the current estimate (as iterate() returns it).
  double residual() const { return m_residual; }
  /// The current estimate, 3 floats per point.
  void read(std::vector<float>& rgb) const;

private:
  const Level1Topology* m_topology = nullptr;
  std::vector<float> m_a;        ///< per edge: 1 / d^2
  std::vector<double> m_a_sum;   ///< per point: A_v
  // Per solve.
  std::vector<std::uint8_t> m_finite;  ///< per point: L0 finite in all channels
  std::vector<double> m_finite_sum;    ///< per point: sum of a over finite neighbours
  std::array<double, 3> m_sigma{0, 0, 0};
  std::vector<float> m_pre;
  // Conjugate-gradient state, 3 per point (channels interleaved).
  std::vector<double> m_x, m_r, m_p, m_q;
  std::array<double, 3> m_rz{0, 0, 0};
  std::array<bool, 3> m_active{false, false, false};
  double m_residual = 0.0;

  double diagonal(std::size_t v, int c) const { return m_a_sum[v] / 6.0 + m_sigma[static_cast<std::size_t>(c)] * m_finite_sum[v]; }
  bool in_system(std::size_t v) const { return m_finite[v] && m_a_sum[v] > 0.0; }
  /// sum of a_vi values_i over v's neighbours, per channel. Points out of the system hold 0 in
  /// x and p (non-finite sources start at 0; p is never set there), so no test is needed.
  void neighbour_sum(std::size_t v, const std::vector<double>& values, double out[3]) const;
  /// q = M p over the points in the system; returns p . q per channel.
  std::array<double, 3> multiply();
  /// z = r / diag folded into p = z + beta p; returns r . z per channel and max |z|.
  void precondition(std::array<double, 3>& rz, double& largest) const;
};

}  // namespace penumbra::render::lighting
