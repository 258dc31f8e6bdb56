// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/light_volume.h
//
// Global lighting for tet meshes: the two-level light volume of Shih, Zhang & Ma ("Advanced
// lighting for unstructured-grid data visualization", eq. 1-12, Algorithm 1), solved on the CPU.
//
// Optical model. Per light k, rho_k(x) is the fraction of the light that reaches x. It obeys the
// steady state of eq. 4, c u . grad(rho) = -sigma_a(x) rho. Read literally (a constant
// absorption sigma_a, eq. 8 applied per time step) the converged light would depend on the light
// speed c and the time step. Here the absorption is defined as sigma_a(x) = c * sigma_a_tilde *
// tau(s(x)), with tau the transfer function's extinction per unit length and sigma_a_tilde the
// user's absorption strength, so the steady state is Beer-Lambert:
//     rho_k(x) = exp(-sigma_a_tilde * integral of tau along the ray from x to light k),
// independent of c and of the time step (eq. 8 with alpha = 1 - exp(-integral of tau) is exactly
// one step of this). Point lights have no 1/r^2 fall-off (eq. 4 has no divergence term).
//
// Level 0: a regular grid over the mesh bounds. Each node takes the scalar of the tet containing
// it (nodes in no tet are "outside" and have zero extinction, so light crosses holes and
// concavities; nodes inside an occluder box are "occluder" and block all light). Eq. 4 is solved
// per light to steady state by the first-order upwind scheme, with the attenuation between a node
// and its upwind neighbours integrated exactly for an extinction linear between them (so a grid
// aligned light reproduces Beer-Lambert exactly); nodes on an inflow face of the grid are 1.
// Directional lights need one sweep ordered along the light; point lights one sweep per octant,
// outward from the light. The grid's memory is capped (see level0_memory_budget_bytes).
//
// Level 1: the mesh vertices. Initial values are level 0 interpolated trilinearly; then
// semi-Lagrangian steps (eq. 6-8) trace back from each vertex by the step h = c dt through the
// tets (the renderer's walk: exits by edge signs in the plane across the ray with one consistent
// tie rule, so rays through vertices, along edges and in face planes walk like nearby generic
// rays; a ray from a boundary vertex along the boundary is pushed inside), take rho at the
// departure point from the corners of its tet, and attenuate by exp(-sigma_a_tilde * integral
// of tau), the integral exact for the linear scalar and the piecewise-linear transfer function. The departure value interpolates the optical depth rescaled
// by the ray's path length, which is exact for Beer-Lambert in a homogeneous medium at any step
// (linear interpolation of rho, the paper's barycentric choice, errs at every step); across shadow
// edges it falls back to linear interpolation of rho. Vertices are processed in order along the
// light (Gauss-Seidel, in parallel within slabs of half a step; internally the points are
// renumbered along a Morton curve, for the cache), so one pass carries the light across the
// mesh; later passes recompute only vertices whose inputs changed, until the largest
// change is below the tolerance. A trace that leaves the mesh (the inflow boundary, a hole, a
// concavity) takes the level-0 value at the exit point, looked up in the empty level-0 nodes
// around it where there are any. The paper's step count (level-0 cell size / mean edge length) is
// what covers one level-0 cell; here the default step is max(mean edge, level-0 cell size), and
// each vertex steps at least twice its longest edge (level1_adaptive_step), so coarse cells of a
// graded mesh do not need one pass per step. The converged light does not depend on the step.
//
// Scattering: the per-light results are combined into one colour field (eq. 9), then one implicit
// (backward-Euler) diffusion step of size sigma_s_tilde per channel (eq. 12):
//     L_v = (L0_v + s * sum_i w_i L_i) / (1 + s * sum_i w_i),  w_i = 6 (1 / d_i^2) / sum_j (1 / d_j^2),
// over the mesh-edge neighbours of v at distances d_i: weights proportional to 1 / d^2 as in the
// paper, normalised to sum to 6 (a regular grid's six unit neighbours) at every vertex. So
// sigma_s_tilde is dimensionless and counts in local edge lengths: the blur radius is about
// sqrt(2 sigma_s_tilde) edges, and the step is equally well conditioned at every vertex, so a
// graded mesh needs no more iterations than a uniform one (with weights in world units its
// smallest cells would make the system stiff). The system is solved to the tolerance by Jacobi
// iterations with Chebyshev acceleration (light_scattering.h: the iteration's eigenvalues are
// real and bounded by 6 s / (1 + 6 s), so the optimal weights are known without estimating
// anything), so the blur depends on sigma_s_tilde, not on the number of iterations a frame
// allows. The step's solution has no new extrema (the matrix is an M-matrix with row sums 1),
// constants stay constant, and non-finite values are left out of every neighbour sum.
// (Tried before: Gauss-Seidel sweeps, convex at every update but about 1.9x the iterations at
// sigma_s_tilde = 1; conjugate gradients on the symmetrised system, half the iterations but each
// streaming four vectors of doubles, 3.5x slower on 1M tets.)
//
// Incremental (Algorithm 1): set_field marks every light changed, set_lights only the lights
// that differ, and update() spends at most a budget of work units or milliseconds, resuming
// where it stopped on the next call; light_rgb() always holds the current estimate. A time
// budget can stop a level-1 pass between two batches of vertices; the indivisible pieces are the
// level-0 resampling after set_field, one level-0 solve (with a moved light's vertex order), a
// full pass's set-up, one batch, the scattering's set-up and one block of a scattering iteration
// (a few ms at 1M tets). A piece starts only if its last duration, plus the copy of the results
// that ends the call, still fits, except the first of a call, so every call makes progress and
// overruns are small. (The CPU scattering's set-up is timed at construction when sigma_s is set,
// so the call that ends the level-1 passes can start the scattering too.) After a level-1 piece only the points it changed are combined and copied
// out. A changed light is warm-started from its previous level-1
// solution, corrected by the change of its level-0 solution; the scattering from its previous
// solution plus the change of its source. A light that did not move keeps its vertex order and
// the tet each vertex's walk starts in; one that moved tries that tet first (a small turn keeps
// most of them) before searching the vertex's star.
//
// GPU solve (options.device set): the same model in OpenGL 4.5 compute shaders, float32. Level 0
// is one dispatch per wavefront of nodes at equal index distance from the light's node (every
// node computed as by the CPU sweep); level 1 is one dispatch per slab group of the same vertex
// order, each vertex reading what the CPU's Gauss-Seidel pass reads, so a pass computes the same
// function of its inputs; the scattering runs the same Chebyshev iterations, to the same
// tolerance. Resampling, vertex order, warm starts and the combination of the lights stay on the
// CPU. Results are read back after every stage, so light_rgb(),
// light_rho(k) and level0_rho(k) mean the same. Stated agreement with the CPU solve (float32
// rounding plus the solve tolerances): level 0 within 1e-5; level 1 within 3e-4 (three default
// propagation tolerances: rounding can make one solve run one pass more) at every vertex, mean
// within 2e-5; scattering within about 6 sigma_s scatter_tolerance max|L| of the exact step on
// each side. Measured on llvmpipe: <= 2e-6 everywhere (tests/unit/lighting/
// gpu_light_volume_test.cpp). Budgets: the same work units and look-ahead, but the indivisible
// pieces are a level-0 solve, a whole level-1 pass (no deadline inside a pass) and a batch of up
// to 8 scattering iterations (never more than the work units left).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "penumbra/core/vec3.h"
#include "penumbra/render/tet_mesh.h"
#include "penumbra/render/transfer_function.h"

namespace penumbra::render {

class GpuDevice;  // penumbra/render/gpu_ray_caster.h

/// A light source with an RGB colour (linear, any non-negative intensity).
struct Light {
  enum class Kind { directional, point };
  Kind kind = Kind::directional;
  /// directional: the direction the light travels (any length > 0); point: the position.
  Vec3d vector{0, 0, -1};
  std::array<double, 3> color{1, 1, 1};

  bool operator==(const Light& o) const {
    return kind == o.kind && vector.x == o.vector.x && vector.y == o.vector.y && vector.z == o.vector.z &&
           color == o.color;
  }
};

/// How the light volume is solved.
enum class LightSolveMode {
  two_level,    ///< level 0, then semi-Lagrangian level 1 (the paper's method)
  level0_only,  ///< level 0 interpolated to the vertices (for comparison)
};

struct LightVolumeOptions {
  /// Level-0 nodes along the longest axis of the mesh bounds (others in proportion), >= 2.
  int level0_resolution = 128;
  /// Level-0 memory: when resolution^3 nodes would need more (13 + 4 * lights bytes per node:
  /// tet id, extinction, mask, sweep scratch, rho per light), the resolution is reduced to the
  /// largest that fits; level0_dims() tells the result.
  /// A budget that does not hold even 4 nodes per axis is an error.
  std::size_t level0_memory_budget_bytes = std::size_t{512} << 20;
  /// Absorption strength sigma_a_tilde (>= 0): rho = exp(-sigma_a * optical depth).
  double sigma_a = 1.0;
  /// Scattering strength sigma_s_tilde per channel (>= 0; 0 = no scattering).
  std::array<double, 3> sigma_s{0.0, 0.0, 0.0};
  /// Level-1 passes stop when no vertex changes by more than this (absolute, rho in [0, 1];
  /// the default is 1/40 of an 8-bit level). With steps shorter than the mean edge (only
  /// without level1_adaptive_step) the change is scaled to a light travel of one mean edge.
  double propagation_tolerance = 1e-4;
  /// Scattering iterations stop when no vertex changes by more than this times max |L| (at
  /// least 9.5e-7: the float iterates settle within a few units in the last place).
  double scatter_tolerance = 1e-4;
  /// Level-1 semi-Lagrangian step h = c * dt in world units; 0 picks max(mean edge length,
  /// largest level-0 spacing).
  double level1_step = 0.0;
  /// Each vertex steps at least twice its longest edge (the steady state does not depend on the
  /// step; this keeps coarse cells of a graded mesh from needing a pass per step). Off: every
  /// vertex takes level1_step exactly, as a time-accurate scheme would.
  bool level1_adaptive_step = true;
  /// Safety caps on iterations per light and for scattering (each counts as one work unit).
  int level1_max_passes = 64;
  int scatter_max_iterations = 2000;
  /// Level-1 walks are recorded (the faces crossed with their crossing points' weights, the
  /// departure weights: about 320 bytes per point and light on a tet mesh) so that a new field
  /// with the same lights re-integrates along them instead of walking again. They are kept while
  /// points x lights x 320 B fits in this budget, else every walk is traced anew (0 turns
  /// recording off).
  std::size_t walk_memory_budget_bytes = std::size_t{1} << 30;
  LightSolveMode mode = LightSolveMode::two_level;
  /// Opaque boxes embedded in the volume (level-0 mask "occluder"; exact in level 1).
  std::vector<Bounds> occluders;
  /// Solve on this GPU (GpuDevice::open) instead of the CPU; null = CPU. The constructor throws
  /// Error(backend_unavailable) when the build has no GPU backend or the device lacks what the
  /// kernels need.
  std::shared_ptr<GpuDevice> device;
};

/// What one update() may spend. A work unit is one level-0 solve of one light, one level-1 pass
/// of one light, or one scattering iteration. Negative / infinite = unlimited.
struct LightBudget {
  int max_work_units = -1;
  double max_ms = std::numeric_limits<double>::infinity();
};

/// What one update() did.
struct LightUpdateReport {
  bool converged = false;     ///< every light and the scattering are at their tolerance
  double residual = 0.0;      ///< largest last change among unfinished stages (0 when converged)
  int work_units = 0;
  int lights_recomputed = 0;  ///< lights whose level-0 solve ran in this call
  int level1_passes = 0;
  int scatter_iterations = 0;
  std::size_t lost_traces = 0;  ///< level-1 walks that hit their step cap (fell back to level 0)
  double resample_ms = 0;       ///< level-0 extinction resampling (after set_field)
  double l0_prop_ms = 0, l0_scatter_ms = 0, l1_prop_ms = 0, l1_scatter_ms = 0, total_ms = 0;
};

/// Level-0 cell classes.
enum class Level0Mask : std::uint8_t { outside = 0, inside = 1, occluder = 2 };

/// Read-only view of the level-0 grid: node (i, j, k) sits at lo + (i, j, k) * spacing, index
/// i + dims[0] * (j + dims[1] * k).
struct Level0View {
  std::array<int, 3> dims{0, 0, 0};
  Vec3d lo, spacing;
  const std::vector<Level0Mask>* mask = nullptr;
  const std::vector<float>* extinction = nullptr;  ///< tau per node (before sigma_a)
};

/// The two-level light volume of one tet mesh. Not thread-safe; update() uses the worker pool.
/// Memory besides the level-0 grid, measured on a 750K-tet block: about 200 bytes per tet (its own
/// copy of the mesh with the points renumbered, the walk records, each point's star, the
/// scattering stencil), and about 310 bytes per point for each light, its recorded walks
/// included (see walk_memory_budget_bytes). The first light's share is allocated (and its pages
/// touched) by the constructor, which also times that light's first level-1 pieces, so that a
/// new volume's first frames spend their budget on the solve (about 40 ms more construction at
/// 1M tets); set_lights hands it to the first light.
class LightVolume {
public:
  LightVolume(std::shared_ptr<const TetMesh> mesh, LightVolumeOptions options = {});
  ~LightVolume();
  LightVolume(LightVolume&&) noexcept;
  LightVolume& operator=(LightVolume&&) noexcept;

  /// New per-point scalars (NaN = no data, zero extinction) or transfer function: resamples
  /// level 0 and marks every light changed. Throws penumbra::Error on bad input.
  void set_field(const std::vector<float>& point_scalars, const TransferFunction& tf);
  /// Replaces the lights; only lights that differ from the previous list at the same index are
  /// recomputed (a colour-only change just recombines).
  void set_lights(std::vector<Light> lights);
  /// Absorption strength: marks every light changed.
  void set_absorption(double sigma_a);
  /// Scattering strengths per channel: re-runs only the scattering.
  void set_scattering(std::array<double, 3> sigma_s);

  /// Algorithm 1, incremental: continues the solve within `budget`.
  LightUpdateReport update(const LightBudget& budget = {});

  /// L(x) per mesh point, 3 floats per point (eq. 9, then eq. 12): what the renderer interpolates.
  const std::vector<float>& light_rgb() const;
  /// rho of light k per mesh point (level 1, before scattering). Copied out of the solver's own
  /// point order on the first call after an update, so not to be called from two threads at once.
  const std::vector<float>& light_rho(std::size_t k) const;
  /// rho of light k per level-0 node.
  const std::vector<float>& level0_rho(std::size_t k) const;
  Level0View level0() const;
  std::array<int, 3> level0_dims() const;
  /// The level-1 step in use (world units).
  double level1_step() const;
  double mean_edge_length() const;
  const LightVolumeOptions& options() const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

/// Double-precision ground truth for tests and benchmarks: the transmittance
/// exp(-sigma_a * integral of tau) from point x to a light, found by intersecting the ray with
/// every tet (a BVH over all tets, independent of the adjacency walk and of level 0), sorting the
/// intervals (gaps are empty space, so the ray continues across holes) and integrating each
/// interval exactly (cut where the scalar crosses a transfer-function breakpoint). A ray that
/// meets an occluder box gives 0.
class LightTransmittanceReference {
public:
  explicit LightTransmittanceReference(std::shared_ptr<const TetMesh> mesh);
  ~LightTransmittanceReference();
  double transmittance(const std::vector<float>& scalars, const TransferFunction& tf, double sigma_a,
                       const Light& light, const Vec3d& x, const std::vector<Bounds>& occluders = {}) const;
  /// Optical depth (integral of tau, without sigma_a) from x to the light, ignoring occluders.
  double optical_depth(const std::vector<float>& scalars, const TransferFunction& tf, const Light& light,
                       const Vec3d& x) const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace penumbra::render
