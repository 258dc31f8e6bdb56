// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/cpu_light_solver.h -- the light volume's kernels on the CPU
#pragma once
#include <vector>

#include "light_scattering.h"
#include "light_solver.h"

namespace penumbra::render::lighting {

/// The light volume solved on the CPU's worker pool: level 0 by level0_sweep.h, level 1 by
/// level1_solve.h (passes that stop at a deadline between batches of vertices), the scattering
/// by light_scattering.h in pieces of whole blocks of an iteration. Its pieces are sized by
/// their timings, so the volume primes those at construction (time_scatter_setup, and the first
/// light's pass timings).
class CpuLightSolver final : public LightSolver {
public:
  /// `scatter_weights`: the mesh's edge weights (scatter_weights()).
  CpuLightSolver(const TetMesh& mesh, const Level1Topology& topology, const std::vector<float>& scatter_weights);

  void move_points(const TetMesh& mesh, const Level1Topology& topology, const std::vector<float>& scatter_weights) override;
  void set_grid(const Level0Grid&) override {}
  void set_field(const Level0Grid&, const Level1Field&) override {}
  void solve_level0(LightState& l, const Level0Grid& grid, double sigma_a, std::vector<float>& rho0) override;
  bool orders_apart() const override { return true; }
  void prepare_order(LightState& l, const Level1Context& ctx) override;
  double expected_level1_ms(const LightState& l) const override;
  Level1Piece level1_pass(LightState& l, const Level1Context& ctx, Clock::time_point deadline) override;
  void restart_scattering() override;
  ScatterPiece scatter_piece(const LightSchedule& schedule, LightCombination& light,
                             const ScatterRequest& request) override;
  double expected_read_back_ms() const override { return m_read_back_ms; }
  void read_scattering(std::vector<float>& colour) override;

  /// Times the scattering's set-up on `light`'s arrays (its source zeroed; twice, the second
  /// past the first touch of the memory), so that a budgeted first scattering plans its set-up
  /// beside other work instead of waiting for a call of its own.
  void time_scatter_setup(LightCombination& light);

private:
  double set_up_scattering(LightCombination& light);
  std::size_t blocks_to_run(const LightSchedule& schedule) const;

  std::size_t m_points;
  std::vector<float> m_sweep_scratch;  // level-0 sweeps
  ScatterPlan m_plan;
  // The scattering's source and iterate in the plan's order, copied in by the set-up and back to
  // point order by read_scattering.
  std::vector<float> m_source, m_iterate;
  ScatterSolve m_solve;
  bool m_setup_stale = true;
  // The last durations (ms; < 0: never timed): the set-up, one block of an iteration, the read-back.
  double m_setup_ms = -1, m_block_ms = -1, m_read_back_ms = 0;
};

}  // namespace penumbra::render::lighting
