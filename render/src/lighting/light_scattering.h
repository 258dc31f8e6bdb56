// render/src/lighting/light_scattering.h -- one implicit diffusion step of the light colour (eq. 12)
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "level1_mesh.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::render::lighting {

/// Edge weights w_i = 6 (1 / d_i^2) / sum_j (1 / d_j^2) of every point's neighbours (see
/// light_volume.h): proportional to 1 / d^2 as in the paper, summing to 6 at every point (a
/// regular grid's six neighbours at unit spacing), so one step of size s blurs by about
/// sqrt(2 s) local edge lengths and is equally well conditioned at every vertex of a graded
/// mesh. Zero-length edges get weight 0.
std::vector<float> scatter_weights(const TetMesh& mesh, const Level1Topology& topology);

/// The sweep runs on this many fixed blocks of points in parallel (fixed, so the result does not
/// depend on the thread count).
inline constexpr std::size_t kScatterChunks = 16;

/// The order a sweep works in: the points along a Morton curve of their positions, cut into
/// kScatterChunks blocks, with the sources, the iterate and each point's edges stored in that
/// order. A point's neighbours then mostly sit just before or after it, so what it gathers is
/// still in cache; in the mesh's own numbering they were scattered over the arrays and the sweep
/// waited on memory for most of its time. Positions, not point ids, index everything below.
struct ScatterPlan {
  std::vector<std::int32_t> order;         ///< the point at each position
  std::vector<std::size_t> chunk_begin;    ///< kScatterChunks + 1 positions
  std::vector<std::int64_t> edge_offsets;  ///< edges of position k: [edge_offsets[k], edge_offsets[k+1])
  std::vector<std::int32_t> edge_ids;      ///< neighbour positions
  std::vector<float> weights;              ///< scatter_weights, in the same order
};
ScatterPlan plan_scatter(const TetMesh& mesh, const Level1Topology& topology, const std::vector<float>& weights);

/// Floats per position in the plan's order: the 3 channels and one of padding, so that a
/// neighbour's colour is one 16-byte load.
inline constexpr std::size_t kPlannedStride = 4;

/// 3 floats per point, from point order to the plan's order (kPlannedStride per position) and back.
void to_plan_order(const ScatterPlan& plan, const std::vector<float>& by_point, std::vector<float>& by_position);
void to_point_order(const ScatterPlan& plan, const std::vector<float>& by_position, std::vector<float>& by_point);

/// One Gauss-Seidel sweep of the backward-Euler step (I - s Laplacian) L = L0 per channel:
///     L_v = (L0_v + s sum_i w_i L_i) / (1 + s sum_i w_i),
/// updating `current` in place; a convex combination of L0_v and the current neighbour values.
/// `pre` and `current` hold kPlannedStride floats per position of the plan. The plan's blocks are swept in
/// parallel: Gauss-Seidel within a block, the previous iterate (`snapshot`, scratch) across
/// blocks. Points whose L0 is not finite are left out of every neighbour sum and take the
/// weighted mean of their finite neighbours (0 without any), so NaN never spreads. Returns the
/// largest change. (Over-relaxation was tried: the matrix is not symmetric and the blocks are
/// coupled Jacobi-wise, and factors above 1.2 diverged while 1.2 saved nothing.)
double scatter_sweep(const ScatterPlan& plan, const std::vector<float>& pre, const std::array<double, 3>& sigma_s,
                     std::vector<float>& current, std::vector<float>& snapshot);

/// A sweep done in pieces, so that a frame's time budget is not left unused for want of room
/// for a whole sweep. The blocks read each other only through the snapshot taken when the sweep
/// begins, so its values do not depend on how its blocks are split between calls.
struct ScatterSweep {
  std::vector<float> snapshot;
  std::vector<std::uint8_t> finite;  ///< per position: its source is finite
  std::size_t next_chunk = 0;        ///< 0: the next piece begins a sweep
  double residual = 0.0;             ///< largest change so far in this sweep
  void restart() { next_chunk = 0; }
};

/// Sweeps blocks [next_chunk, next_chunk + chunks) (at least one; beginning the sweep when
/// next_chunk is 0). Returns true when that finished the sweep: its largest change is then in
/// `sweep.residual`, and the next piece begins a new sweep.
bool scatter_sweep_part(const ScatterPlan& plan, const std::vector<float>& pre, const std::array<double, 3>& sigma_s,
                        std::vector<float>& current, ScatterSweep& sweep, std::size_t chunks);

}  // namespace penumbra::render::lighting
