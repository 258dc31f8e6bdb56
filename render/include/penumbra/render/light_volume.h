// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/light_volume.h -- global lighting for tet meshes
//
// The two-level light volume of Shih, Zhang & Ma ("Advanced lighting for unstructured-grid data
// visualization"). Per light k, rho_k(x) is the fraction of the light that reaches mesh point x:
// Beer-Lambert along the ray to the light, rho_k = exp(-sigma_a * integral of the transfer
// function's extinction), with holes and concavities crossed without loss and occluder boxes
// opaque. It is solved on a regular grid over the mesh (level 0) and refined at the mesh
// vertices by semi-Lagrangian steps (level 1); the lights are summed into one colour per point
// and blurred by one implicit diffusion step of strength sigma_s (scattering). update()
// continues the solve within a per-call budget, so light_rgb() always holds the current
// estimate. Solved on the CPU, or on a GPU with LightVolumeOptions::device. The algorithm, the
// design choices and the measurements behind them: docs/light_volume.md.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "penumbra/core/vec3.h"
#include "penumbra/render/tet_mesh.h"
#include "penumbra/render/transfer_function.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

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
  /// A volume over one rank's cells of a mesh split over ranks: level 0 spans these bounds (the
  /// union of every rank's, the same on every rank) instead of the mesh's, so that the ranks'
  /// grids share their nodes and LightVolume::combine_level0 can merge them. Empty: the mesh's.
  Bounds level0_bounds;
};

/// What one update() may spend. A work unit is one level-0 solve of one light, one level-1 pass
/// of one light, or one scattering iteration. Negative / infinite = unlimited. A piece of work
/// starts only if it is expected, from its last duration, to end within max_ms; the first of a
/// call always starts, so every call makes progress and overruns by at most about one piece (on
/// the CPU a batch of vertices or a block of a scattering iteration, on the GPU a whole level-1
/// pass or up to 8 scattering iterations).
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
/// Memory besides the level-0 grid: about 200 bytes per tet and about 310 bytes per point for
/// each light (its recorded walks included, see walk_memory_budget_bytes). The constructor
/// allocates the first light's share and times the first pieces of the solve, so that a new
/// volume's first updates spend their budget on the solve; set_lights hands that share to the
/// first light.
class LightVolume {
public:
  LightVolume(std::shared_ptr<const TetMesh> mesh, LightVolumeOptions options = {});
  ~LightVolume();
  LightVolume(LightVolume&&) noexcept;
  LightVolume& operator=(LightVolume&&) noexcept;

  /// New per-point scalars (NaN = no data, zero extinction) or transfer function: resamples
  /// level 0 and marks every light changed. Throws penumbra::Error on bad input.
  void set_field(const std::vector<float>& point_scalars, const TransferFunction& tf);
  /// The same mesh with its points moved (move_tet_mesh; a Lagrangian mesh a step later): the
  /// level-0 grid, the edge lengths and the solver's geometry follow the points, and every light
  /// is solved again like a light that moved, its level-1 solution kept as the warm start.
  /// Throws Error(invalid_argument) when `moved` is null or has other point or tet counts.
  void move_points(std::shared_ptr<const TetMesh> moved);
  /// Replaces the lights; only lights that differ from the previous list at the same index are
  /// recomputed (a colour-only change just recombines).
  void set_lights(std::vector<Light> lights);
  /// Absorption strength: marks every light changed.
  void set_absorption(double sigma_a);
  /// Scattering strengths per channel: re-runs only the scattering.
  void set_scattering(std::array<double, 3> sigma_s);

  /// The level-0 extinction and mask, as this volume's cells give them, merged with the other
  /// ranks' (a volume over one rank's cells, options().level0_bounds): `combine` replaces both by
  /// their element-wise maximum over the ranks, which is the whole mesh's grid, since a node lies
  /// in some rank's cells exactly when it is inside and each rank gives it the same extinction.
  /// Resamples first when set_field left that pending. Call it on every rank after set_field and
  /// before update (collective whenever `combine` is); level-1 walks that leave this rank's cells
  /// then continue in the merged level 0, and shadows cast by other ranks' cells are kept.
  using Level0Combine = std::function<void(std::vector<float>& tau, std::vector<Level0Mask>& mask)>;
  void combine_level0(const Level0Combine& combine);

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

/// Per listed point, whether the ray from it towards `light` runs into one of `mesh`'s tets (1)
/// or leaves the mesh at the point (0); a ray in the plane of a tet's face counts as entering.
/// Where ranks share a point, a rank whose cells the ray enters holds its level-1 value: its walk
/// integrates the extinction there, where the others read level 0 at the point.
std::vector<std::uint8_t> rays_enter_mesh(const TetMesh& mesh, const std::vector<std::int32_t>& points,
                                          const Light& light);

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

PNB_PUBLIC_END
