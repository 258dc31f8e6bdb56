// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/cpu_light_solver.cpp -- the light volume's kernels on the CPU
#include "cpu_light_solver.h"

#include <algorithm>
#include <atomic>

#include "level0_sweep.h"
#include "penumbra/core/elapsed.h"

namespace penumbra::render::lighting {

CpuLightSolver::CpuLightSolver(const TetMesh& mesh, const Level1Topology& topology,
                               const std::vector<float>& scatter_weights)
    : m_points(mesh.points.size()), m_plan(plan_scatter(mesh, topology, scatter_weights)) {}

void CpuLightSolver::move_points(const TetMesh& mesh, const Level1Topology& topology,
                                 const std::vector<float>& scatter_weights) {
  m_plan = plan_scatter(mesh, topology, scatter_weights);
  m_setup_stale = true;
}

void CpuLightSolver::solve_level0(LightState& l, const Level0Grid& grid, double sigma_a, std::vector<float>& rho0) {
  lighting::solve_level0(grid, l.light, sigma_a, rho0, m_sweep_scratch);
}

void CpuLightSolver::prepare_order(LightState& l, const Level1Context& ctx) { l.ensure_order(ctx, ctx.record_walks); }

double CpuLightSolver::expected_level1_ms(const LightState& l) const {
  // A pass stops at the deadline by itself, after pieces it sizes to fit (batches down to
  // kLevel1MinBatch vertices, slices of start hints); it starts only with room for its first
  // piece, and a full pass also for its set-up.
  const PassState& ps = l.pass_state;
  if (ps.vertex_ms < 0) return -1.0;
  const bool starts_full = !ps.in_pass && ps.departure_corners.size() != m_points;
  const bool hints_next = starts_full || ps.hint_next < ps.hint_end;
  const double first = std::max(ps.vertex_ms * static_cast<double>(kLevel1MinBatch), hints_next ? ps.hint_slice_ms : 0.0);
  if (!starts_full) return first;
  return ps.full_setup_ms < 0 ? -1.0 : first + ps.full_setup_ms;
}

Level1Piece CpuLightSolver::level1_pass(LightState& l, const Level1Context& ctx, Clock::time_point deadline) {
  prepare_order(l, ctx);
  std::atomic<std::size_t> lost{0};
  const bool finished = lighting::level1_pass(ctx, l.light, l.rho0, l.order, l.rho1, l.pass_state, lost, deadline);
  return {finished, lost.load(), &l.pass_state.changed_now};
}

void CpuLightSolver::restart_scattering() {
  m_setup_stale = true;
  m_solve.restart();
}

// The set-up, a piece of its own: the source and the start in the plan's order, the tolerance's
// scale, which sources are finite. Returns its duration.
double CpuLightSolver::set_up_scattering(LightCombination& light) {
  return timed_ms([&] {
    light.source_scale();  // kept for the iterations' tolerance
    to_plan_order(m_plan, light.source(), m_source);
    to_plan_order(m_plan, light.colour(), m_iterate);
    scatter_prepare(m_plan, m_source, m_iterate, m_solve);
    m_setup_stale = false;
  });
}

void CpuLightSolver::time_scatter_setup(LightCombination& light) {
  for (int run = 0; run < 2; ++run) {
    light.zero_source();
    m_setup_ms = set_up_scattering(light);
  }
  light.zero_source();
  restart_scattering();
}

// Blocks of the current iteration to run now (0: none fits): as many as the time budget has room
// for, at least two (one per core) unless this is the call's first piece; one, as a probe, when
// a block was never timed.
std::size_t CpuLightSolver::blocks_to_run(const LightSchedule& schedule) const {
  const std::size_t left = kScatterChunks - m_solve.next_chunk;
  if (!schedule.has_time_limit()) return schedule.allows(m_block_ms < 0 ? -1.0 : m_block_ms * left) ? left : 0;
  if (!schedule.allows(0.0)) return 0;  // the work-unit cap, or no room at all
  if (m_block_ms < 0) return 1;
  const std::size_t fit = schedule.pieces_that_fit(m_block_ms);
  if (schedule.ran_any() && fit < 2) return 0;
  return std::min(left, std::max<std::size_t>(fit, 2));
}

ScatterPiece CpuLightSolver::scatter_piece(const LightSchedule& schedule, LightCombination& light,
                                           const ScatterRequest& request) {
  if (m_setup_stale) {
    if (!schedule.allows(m_setup_ms)) return {};
    m_setup_ms = set_up_scattering(light);
    return {true, 0, 0.0};
  }
  const std::size_t blocks = blocks_to_run(schedule);
  if (blocks == 0) return {};
  bool whole = false;
  const double ms = timed_ms(
      [&] { whole = scatter_iteration_part(m_plan, m_source, request.sigma_s, m_iterate, m_solve, blocks); });
  m_block_ms = ms / static_cast<double>(blocks);
  if (!whole) return {true, 0, 0.0};
  return {true, 1, m_solve.residual};
}

void CpuLightSolver::read_scattering(std::vector<float>& colour) {
  m_read_back_ms = timed_ms([&] { to_point_order(m_plan, m_iterate, colour); });
}

}  // namespace penumbra::render::lighting
