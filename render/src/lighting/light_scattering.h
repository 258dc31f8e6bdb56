// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/light_scattering.h -- one implicit diffusion step of the light colour (eq. 12)
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "level1_mesh.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::render::lighting {

/// Edge weights w_i = 6 (1 / d_i^2) / sum_j (1 / d_j^2) of every point's neighbours (see
/// docs/light_volume.md): proportional to 1 / d^2 as in the paper, summing to 6 at every point (a
/// regular grid's six neighbours at unit spacing), so one step of size s blurs by about
/// sqrt(2 s) local edge lengths and is equally well conditioned at every vertex of a graded
/// mesh. Zero-length edges get weight 0.
std::vector<float> scatter_weights(const TetMesh& mesh, const Level1Topology& topology);

/// The sweep runs on this many fixed blocks of points in parallel (fixed, so the result does not
/// depend on the thread count).
inline constexpr std::size_t kScatterChunks = 16;

/// Positions per slice: a slice's neighbour sums are gathered column by column (see ScatterPlan).
inline constexpr std::size_t kScatterSlice = 8;

/// The order a sweep works in: the points along a Morton curve of their positions, cut into
/// kScatterChunks blocks, with the sources, the iterate and each point's edges stored in that
/// order. A point's neighbours then mostly sit just before or after it, so what it gathers is
/// still in cache, where the mesh's own numbering scatters them over the arrays. Positions, not
/// point ids, index everything below.
/// The edges are stored by slices of kScatterSlice positions: slice s has as many columns as its
/// positions' largest neighbour count, column k holding the k-th neighbour of each position of
/// the slice, so that a sweep runs one loop per slice over its columns instead of one loop per
/// point of 5 to 26 neighbours, whose end the branch predictor would miss at every point. A
/// position with fewer neighbours has weight 0 (and its own position as id) in the columns it
/// lacks; to keep that padding small, the points within each window of kDegreeWindow consecutive
/// positions of the curve are sorted by their number of neighbours.
struct ScatterPlan {
  static constexpr std::size_t kDegreeWindow = 128;
  std::vector<std::int32_t> order;        ///< the point at each position
  std::vector<std::size_t> chunk_begin;   ///< kScatterChunks + 1 positions: multiples of kScatterSlice, or the point count (blocks past the last point are empty)
  std::vector<std::int64_t> slice_begin;  ///< per slice + 1: its first entry (columns x kScatterSlice entries)
  std::vector<std::int32_t> ids;          ///< per entry: the neighbour's position
  std::vector<float> weights;             ///< per entry: scatter_weights (0 in padding)
  std::vector<float> weight_sums;         ///< per position: the sum of its weights (6, or 0 alone)
  std::size_t slices() const { return slice_begin.size() - 1; }
};
ScatterPlan plan_scatter(const TetMesh& mesh, const Level1Topology& topology, const std::vector<float>& weights);

/// Floats per position in the plan's order: the 3 channels and one of padding, so that a
/// neighbour's colour is one 16-byte load.
inline constexpr std::size_t kPlannedStride = 4;

/// 3 floats per point, from point order to the plan's order (kPlannedStride per position) and back.
void to_plan_order(const ScatterPlan& plan, const std::vector<float>& by_point, std::vector<float>& by_position);
void to_point_order(const ScatterPlan& plan, const std::vector<float>& by_position, std::vector<float>& by_point);

/// The backward-Euler step (I - s Laplacian) L = L0 per channel is solved by Jacobi iterations
///     J(L)_v = (L0_v + s sum_i w_i L_i) / (1 + s sum_i w_i)
/// with Chebyshev acceleration (Golub & Varga's semi-iterative method):
///     L_{k+1} = L_{k-1} + omega_{k+1} (J(L_k) - L_{k-1}),
///     omega_1 = 1, omega_2 = 1 / (1 - rho^2 / 2), omega_{k+1} = 1 / (1 - rho^2 omega_k / 4).
/// J's iteration matrix is a positive diagonal times the symmetric matrix of 1 / d^2 weights, so
/// its eigenvalues are real, and they lie in [-rho, rho], rho = 6 s / (1 + 6 s) (the weights of a
/// point sum to at most 6). The error then falls by about rho / (1 + sqrt(1 - rho^2)) per
/// iteration instead of rho (Jacobi) or about rho^2 (Gauss-Seidel): at s = 1, 0.57 against 0.86
/// and 0.73, and far fewer iterations for larger s. Every iteration reads the previous iterate
/// only, so the blocks run in parallel and the result does not depend on the thread count.
/// Points whose L0 is not finite are left out of every neighbour sum and take the weighted mean
/// of their finite neighbours (0 without any), so NaN never spreads. Intermediate iterates may
/// overshoot by about the remaining error; the converged one is the step's solution to the
/// tolerance, which has no new extrema.
/// Chebyshev's weights for iteration k + 1 (k finished since the restart) from those of
/// iteration k, per channel: omega_1 = 1, omega_2 = 1 / (1 - rho^2 / 2),
/// omega_{k+1} = 1 / (1 - rho^2 omega_k / 4), rho = 6 s / (1 + 6 s). CPU and GPU both use it.
void chebyshev_weights(int k, const std::array<double, 3>& sigma_s, std::array<double, 3>& omega);

struct ScatterSolve {
  std::vector<float> other;          ///< L_{k-1} while iteration k + 1 runs, overwritten by L_{k+1}
  std::vector<std::uint8_t> finite;  ///< per position: its source is finite
  /// Only when some source is not finite: the plan's weights with those points' weights 0, and
  /// the sums of what is left (the plan's own are used otherwise).
  std::vector<float> masked_weights, masked_sums;
  bool masked = false;
  int iterations = 0;                ///< finished since the restart
  std::array<double, 3> omega{1.0, 1.0, 1.0};
  bool prepared = false;       ///< finite and the masked weights are set for this solve
  std::size_t next_chunk = 0;  ///< 0: the next piece begins an iteration
  double residual = 0.0;       ///< largest change so far in this iteration
  void restart() {
    prepared = false;
    next_chunk = 0;
    iterations = 0;
  }
};

/// What a solve sets up once before its first iteration (scatter_iteration_part does it when it
/// has not been done): which sources are finite, the weights without the others, and a start
/// `current` without non-finite values. A piece of its own in a frame budget.
void scatter_prepare(const ScatterPlan& plan, const std::vector<float>& pre, std::vector<float>& current,
                     ScatterSolve& solve);
/// Runs blocks [next_chunk, next_chunk + chunks) of an iteration (at least one; beginning the
/// iteration when next_chunk is 0), so that a frame's time budget is not left unused for want of
/// room for a whole one. `current` (kPlannedStride floats per position of the plan) holds the
/// last finished iterate throughout; returns true when this piece finished the iteration: it is
/// then in `current`, its largest change in `solve.residual`.
bool scatter_iteration_part(const ScatterPlan& plan, const std::vector<float>& pre, const std::array<double, 3>& sigma_s,
                            std::vector<float>& current, ScatterSolve& solve, std::size_t chunks);

/// One whole iteration (scatter_iteration_part over every block); returns its largest change.
double scatter_iteration(const ScatterPlan& plan, const std::vector<float>& pre, const std::array<double, 3>& sigma_s,
                         std::vector<float>& current, ScatterSolve& solve);

}  // namespace penumbra::render::lighting
