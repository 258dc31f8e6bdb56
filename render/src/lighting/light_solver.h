// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/light_solver.h -- what a light volume's update asks of the solver
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "level0_grid.h"
#include "level1_mesh.h"
#include "level1_solve.h"
#include "light_combination.h"
#include "light_schedule.h"
#include "light_state.h"

namespace penumbra::render::lighting {

/// What a level-1 piece did.
struct Level1Piece {
  bool finished = false;  ///< the pass finished; its largest change is in the light's pass_state.residual
  std::size_t lost = 0;   ///< walks that hit their move cap
  /// The points whose value changed; null: any point may have.
  const std::vector<std::int32_t>* changed = nullptr;
};

/// What the next scattering piece is asked to do.
struct ScatterRequest {
  std::array<double, 3> sigma_s{0, 0, 0};
  double relative_tolerance = 0;  ///< LightVolumeOptions::scatter_tolerance
  int iterations_left = 0;        ///< before the iteration cap
  double residual = 0;            ///< the last finished iteration's change
};

/// What a scattering piece did.
struct ScatterPiece {
  bool ran = false;    ///< false: the schedule had no room for it
  int iterations = 0;  ///< iterations it finished (0: a set-up or part of an iteration)
  double residual = 0; ///< the last finished iteration's largest change (when iterations > 0)
};

/// The kernels of the light volume: the level-0 sweep, the level-1 passes and the scattering
/// iterations, on the CPU (CpuLightSolver) or on a GPU (DeviceLightSolver), which solve the same
/// model. The volume keeps what both share: the grid and its resampling, the vertex orders, the
/// warm starts and the combination of the lights. Each piece a solver runs is one the schedule
/// allowed by its expected cost, which the solver tracks for its own pieces.
class LightSolver {
public:
  virtual ~LightSolver() = default;

  /// The same mesh with its points moved (the volume's copy, in its point order): the solver's
  /// positions, edge lengths and scattering weights follow; the topology and each light's data stay.
  virtual void move_points(const TetMesh& mesh, const Level1Topology& topology, const std::vector<float>& scatter_weights) = 0;
  /// A new level-0 grid (at construction, or a resolution reduced for more lights).
  virtual void set_grid(const Level0Grid& grid) = 0;
  /// A resampled field: the grid's extinction and the level-1 field.
  virtual void set_field(const Level0Grid& grid, const Level1Field& field) = 0;

  /// Light l's level-0 solve into `rho0` (per node), before l takes it (LightState::take_level0).
  virtual void solve_level0(LightState& l, const Level0Grid& grid, double sigma_a, std::vector<float>& rho0) = 0;

  /// Whether building a light's vertex order is a piece of its own (else its next pass builds it).
  virtual bool orders_apart() const = 0;
  /// Builds light l's vertex order if it is not current.
  virtual void prepare_order(LightState& l, const Level1Context& ctx) = 0;
  /// The expected duration of light l's next level-1 piece (ms; < 0: never timed).
  virtual double expected_level1_ms(const LightState& l) const = 0;
  /// Light l's level-1 pass, or as much of it as ends by `deadline` when the solver can stop
  /// inside a pass; the next call resumes it.
  virtual Level1Piece level1_pass(LightState& l, const Level1Context& ctx, Clock::time_point deadline) = 0;

  /// The scattering starts over from a new source.
  virtual void restart_scattering() = 0;
  /// The next scattering piece, if `schedule` allows it, from `light`'s source and colour.
  virtual ScatterPiece scatter_piece(const LightSchedule& schedule, LightCombination& light,
                                     const ScatterRequest& request) = 0;
  /// The expected duration of read_scattering (ms), which ends a call that scatters.
  virtual double expected_read_back_ms() const = 0;
  /// The scattering's iterate into `colour` (3 floats per point), after a call's pieces.
  virtual void read_scattering(std::vector<float>& colour) = 0;
};

}  // namespace penumbra::render::lighting
