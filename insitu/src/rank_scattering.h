// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/rank_scattering.h -- the light volume's scattering over the points of every rank
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "penumbra/render/tet_mesh.h"
#include "rank_group.h"
#include "shared_points.h"

namespace penumbra::insitu {

/// The light volume's scattering (one backward-Euler diffusion step of the light colour,
/// (I - s Laplacian) L = L0 per channel; docs/light_volume.md) solved over the ranks' points as
/// one mesh. Each point's neighbours are the other ends of its edges on any rank, weighted
/// 6 (1 / d^2) / sum_j (1 / d^2) as in one process; a point on a partition boundary gathers its
/// edges from every rank that holds it, each edge counted once (by the lowest rank that has it).
/// Each Jacobi iteration (Chebyshev-accelerated, as in one process) exchanges the boundary
/// points' partial sums with the ranks that share them and reduces the largest change, so every
/// rank runs the same iterations and the shared points take the same values everywhere.
class RankScattering {
public:
  /// Collective: the ranks agree which shared edges each counts, and the shared points' weight
  /// sums. `mesh` is this rank's tets in the ranks' common frame.
  RankScattering(RankGroup& group, const render::TetMesh& mesh, const SharedPoints& shared);

  struct Report {
    int iterations = 0;
    double residual = 0;  ///< the last iteration's largest change (over every rank)
    bool converged = false;
  };
  /// Solves for `sigma_s` with `source` (3 floats per point, finite) into `light`, which holds
  /// the start (the last step's solution, or the source). Iterates until no point changes by more
  /// than `tolerance` times the largest |source| over the ranks, at most `max_iterations` times.
  /// Collective: every rank runs the same iterations.
  Report solve(RankGroup& group, const std::vector<float>& source, const std::array<double, 3>& sigma_s,
               double tolerance, int max_iterations, std::vector<float>& light) const;

private:
  /// One Jacobi sweep: J(current) per point into `next`.
  void jacobi(RankGroup& group, const std::vector<float>& source, const std::array<double, 3>& sigma_s,
              const std::vector<double>& current, std::vector<double>& next) const;

  const SharedPoints& m_shared;
  std::vector<std::int64_t> m_offsets;      ///< per point: its counted edges [offsets[p], offsets[p + 1])
  std::vector<std::int32_t> m_neighbours;   ///< the other end of each counted edge
  std::vector<double> m_inverse_square;     ///< 1 / d^2 of each counted edge (in the common frame)
  std::vector<double> m_inverse_sum;        ///< per point: sum of 1 / d^2 over its edges on every rank
  std::vector<std::int32_t> m_slot_of;      ///< per point: its SharedPoints slot, or -1
};

}  // namespace penumbra::insitu
