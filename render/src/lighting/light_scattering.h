// render/src/lighting/light_scattering.h -- the weights of the implicit diffusion step (eq. 12)
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
/// mesh. Zero-length edges get weight 0. The GPU's Jacobi iteration reads these; the CPU solves
/// the same step in its symmetric form (ScatterSolver).
std::vector<float> scatter_weights(const TetMesh& mesh, const Level1Topology& topology);

}  // namespace penumbra::render::lighting
