// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/light_state.h -- one light of a light volume: its solution and its progress
#pragma once
#include <cmath>
#include <memory>
#include <vector>

#include "level1_solve.h"
#include "penumbra/render/light_volume.h"

namespace penumbra::render::lighting {

/// What a solver keeps per light beside the light's host arrays (the device solver: the light's
/// buffers). Owned by the light, so it moves with it when the lights are reordered.
struct SolverLightData {
  virtual ~SolverLightData() = default;
};

/// One light's level-0 and level-1 solution, per-point arrays in the volume's point order.
struct LightState {
  enum class Stage { level0, level1, done };

  Light light;
  Stage stage = Stage::level0;
  std::vector<float> rho0;         ///< per level-0 node
  std::vector<float> rho0_vertex;  ///< level 0 at the mesh points (initial values; warm-start reference)
  std::vector<float> rho1;         ///< per mesh point
  /// rho1 in the caller's point order, copied when light_rho asks for it: nothing renders from
  /// it, so the frame budget does not pay for it.
  mutable std::vector<float> rho1_out;
  mutable bool rho1_out_stale = true;
  VertexOrder order;
  PassState pass_state;
  bool order_valid = false;
  bool has_solution = false;
  int passes = 0;
  double residual = HUGE_VAL;
  bool converged = false;  ///< false when the pass cap stopped it
  std::unique_ptr<SolverLightData> solver_data;

  /// The light moved (or the step changed): its vertex order and walks are stale, and each
  /// vertex's start tet becomes a hint for the next walk.
  void forget_direction();
  /// Builds the vertex order for ctx's mesh and step, and sizes the walk state for it (its walks
  /// recorded if `record_walks`), unless the order is current. Returns whether it built one.
  bool ensure_order(const Level1Context& ctx, bool record_walks);
  /// Takes a new level-0 solution: `nodes` per node and `at_vertex` its values at the points.
  /// Level 1 starts from `at_vertex`, or from the previous level-1 solution scaled by how level 0
  /// changed at each point (a warm start); in level0_only mode the light is then done.
  /// `at_vertex` gets the replaced values' storage, for the next solve to reuse.
  void take_level0(std::vector<float> nodes, std::vector<float>& at_vertex, LightSolveMode mode);
  /// Counts a finished level-1 pass whose largest change (scaled to a light travel of one mean
  /// edge) was `change`: the light is done when it is below `tolerance` or after `max_passes`.
  void count_pass(double change, double tolerance, int max_passes);
};

}  // namespace penumbra::render::lighting
