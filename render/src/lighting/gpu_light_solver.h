// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/gpu_light_solver.h -- the light-volume kernels on the GPU (OpenGL 4.5 compute)
//
// The same model as the CPU solve (docs/light_volume.md), in float32 on the device:
//  - level 0: the upwind sweep of level0_sweep.h. A node depends only on its upwind neighbours,
//    which are one step closer (in index distance |i - c_i| + |j - c_j| + |k - c_k|) to the
//    light's node c (directional lights: c is a corner just outside the grid). All nodes at one
//    distance are independent, so the sweep is one dispatch per distance ("wavefront"), every
//    octant of a point light at once. Each node is computed exactly as on the CPU.
//  - level 1: the Gauss-Seidel pass of level1_solve.h, one dispatch per slab group of the CPU's
//    vertex order (order_vertices): a vertex reads the new value of a corner in an earlier group
//    and the old value otherwise, exactly what the CPU's pass reads, so a pass computes the same
//    function of its inputs. Every ordered vertex is recomputed each pass (the CPU skips those
//    whose inputs did not change; they would reproduce their value). A closing dispatch
//    publishes the pass and takes the largest change.
//  - scattering: the CPU's Chebyshev-accelerated Jacobi iterations of the same implicit step
//    (light_scattering.h), to the same tolerance on the largest change.
// Level-0 resampling, vertex order, warm starts and the combination of the lights stay on the
// CPU; their inputs are uploaded when they change and every result is read back, so the CPU-side
// vectors (light_rho, level0_rho, light_rgb) always hold the current estimate.
#pragma once
#include <array>
#include <cstddef>
#include <memory>
#include <vector>

#include "level0_grid.h"
#include "level1_mesh.h"
#include "level1_solve.h"
#include "penumbra/render/light_volume.h"

namespace penumbra::render {
class GpuDevice;
}

namespace penumbra::render::lighting {

/// Device buffers of one light (its level-0 and level-1 solution, vertex order, start tets).
struct GpuLightBuffers;

class GpuLightSolver {
public:
  /// Uploads the mesh, its topology, the scattering weights and the occluder boxes; compiles the
  /// kernels. Throws
  /// Error(backend_unavailable) without a GPU backend or when the device lacks what the kernels
  /// need, Error(out_of_memory) when the buffers do not fit.
  GpuLightSolver(std::shared_ptr<GpuDevice> device, const TetMesh& mesh, const Level1Topology& topology,
                 const std::vector<float>& scatter_weights, const std::vector<Bounds>& occluders);
  ~GpuLightSolver();
  GpuLightSolver(const GpuLightSolver&) = delete;
  GpuLightSolver& operator=(const GpuLightSolver&) = delete;

  /// The same mesh with its points moved: uploads the points (in the moved mesh's frame) with
  /// their longest edges and the scattering weights; the programs and the topology stay.
  void move_points(const TetMesh& mesh, const Level1Topology& topology, const std::vector<float>& scatter_weights);
  /// A new grid (after construction or a change of resolution): uploads its mask and geometry.
  void set_grid(const Level0Grid& grid);
  /// A new field: the grid's extinction, the scalars per point and the extinction table.
  void set_field(const Level0Grid& grid, const Level1Field& field);

  std::shared_ptr<GpuLightBuffers> new_light();

  /// The level-0 solve of `light` into the light's device buffer; `rho0` gets a copy.
  void solve_level0(GpuLightBuffers& buffers, const Light& light, double sigma_a, std::vector<float>& rho0);
  /// A new vertex order for the light (its direction changed): uploads it, forgets start tets.
  void set_order(GpuLightBuffers& buffers, const VertexOrder& order);
  /// New level-1 values from the CPU (initial values, warm start).
  void set_rho1(GpuLightBuffers& buffers, const std::vector<float>& rho1);
  /// One whole semi-Lagrangian pass; reads the result back into rho1. Returns the largest
  /// change; `lost` gets the walks that hit their move cap.
  double level1_pass(GpuLightBuffers& buffers, const Light& light, const Level1Context& ctx, std::vector<float>& rho1,
                     std::size_t& lost);

  /// The scattering's source (eq. 9) and its starting iterate (3 floats per point each).
  void set_scatter_source(const std::vector<float>& pre, const std::vector<float>& start);
  /// Runs one batch of (Chebyshev-accelerated) Jacobi iterations: at most `max_iterations` and at most 8 (one
  /// read-back of the changes per batch), stopping after the first whose largest change is <=
  /// tolerance. Returns the iterations run; `residual` gets the last checked one's change.
  int scatter(int max_iterations, double tolerance, const std::array<double, 3>& sigma_s, double& residual);
  /// The current scattering iterate (3 floats per point) into `rgb`.
  void read_scatter(std::vector<float>& rgb);

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace penumbra::render::lighting
