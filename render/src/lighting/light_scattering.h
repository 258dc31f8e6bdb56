// render/src/lighting/light_scattering.h -- one implicit diffusion step of the light colour (eq. 12)
#pragma once
#include <array>
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

/// One Gauss-Seidel sweep of the backward-Euler step (I - s Laplacian) L = L0 per channel:
///     L_v = (L0_v + s sum_i w_i L_i) / (1 + s sum_i w_i),
/// updating `current` (3 floats per point) in place; a convex combination of L0_v and the
/// current neighbour values. The points are cut into kScatterChunks blocks swept in parallel:
/// Gauss-Seidel within a block, the previous iterate (`snapshot`, scratch) across blocks.
/// Points whose L0 is not finite are left out of every neighbour sum and take the weighted mean
/// of their finite neighbours (0 without any), so NaN never spreads. Returns the largest change.
/// (Over-relaxation was tried: the matrix is not symmetric and the blocks are coupled
/// Jacobi-wise, and factors above 1.2 diverged while 1.2 saved nothing.)
double scatter_sweep(const Level1Topology& topology, const std::vector<float>& weights, const std::vector<float>& pre,
                     const std::array<double, 3>& sigma_s, std::vector<float>& current, std::vector<float>& snapshot);

}  // namespace penumbra::render::lighting
