// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/light_state.cpp -- one light of a light volume: its solution and its progress
#include "light_state.h"

#include <algorithm>

#include "penumbra/core/thread_pool.h"

namespace penumbra::render::lighting {

void LightState::forget_direction() {
  order_valid = false;
  for (std::int32_t& start : pass_state.start_tet) start = hint_start(start);
  pass_state.forget_walks();
}

bool LightState::ensure_order(const Level1Context& ctx, bool record_walks) {
  if (order_valid) return false;
  order = order_vertices(ctx.mesh, ctx.topology, light, ctx.step, std::move(order));
  // The per-vertex walk state is sized here too, not inside the first batch of a pass, where its
  // allocation would come on top of that batch's share of the budget.
  pass_state.prepare_walks(ctx.mesh.points.size(), record_walks);
  order_valid = true;
  return true;
}

void LightState::take_level0(std::vector<float> nodes, std::vector<float>& at_vertex, LightSolveMode mode) {
  const bool level0_only = mode == LightSolveMode::level0_only;
  if (level0_only || !has_solution) {
    rho1 = at_vertex;
  } else {
    // Warm start: keep the previous level-1 detail, scaled by how level 0 changed.
    parallel_for(at_vertex.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
      for (std::size_t p = b; p < e; ++p) {
        const double before = rho0_vertex[p];
        const double v = before > 1e-6 ? rho1[p] * (at_vertex[p] / before) : at_vertex[p];
        rho1[p] = static_cast<float>(std::clamp(v, 0.0, 1.0));
      }
    });
  }
  rho0 = std::move(nodes);
  std::swap(rho0_vertex, at_vertex);
  has_solution = true;
  pass_state.clear();  // the vertex order and start tets depend only on the light: kept
  passes = 0;
  residual = HUGE_VAL;
  converged = level0_only;
  stage = level0_only ? Stage::done : Stage::level1;
}

void LightState::count_pass(double change, double tolerance, int max_passes) {
  residual = change;
  ++passes;
  converged = residual <= tolerance;
  if (converged || passes >= max_passes) stage = Stage::done;
}

}  // namespace penumbra::render::lighting
