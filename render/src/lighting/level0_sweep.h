// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level0_sweep.h -- steady-state upwind solve of eq. 4 on the level-0 grid
#pragma once
#include <vector>

#include "level0_grid.h"

namespace penumbra::render::lighting {

/// Solves c u . grad(rho) = -c sigma_a tau rho to steady state on the level-0 nodes with the
/// first-order upwind scheme, fitted exponentially: node i takes
///     rho_i = sum_a w_a rho_(i - s_a e_a) exp(-sigma_a ds (tau_i + tau_(i - s_a e_a)) / 2),
/// w_a = (|u_a| / h_a) / sum_b (|u_b| / h_b), ds = 1 / sum_b (|u_b| / h_b), s_a the sign of u_a.
/// Without absorption this is exactly the upwind scheme's steady state (its fixed point for any
/// c and dt); the exponential makes a grid-aligned light exact Beer-Lambert rather than
/// 1 / (1 + sigma tau h)^n. Weights are convex and factors <= 1, so rho stays in [0, 1] with no
/// oscillation. A node with an upwind neighbour outside the grid is on an inflow face: its
/// characteristic comes straight from empty space, so it is a Dirichlet node with rho = 1.
/// Directional lights: one sweep ordered along u. Point lights: one sweep per octant, outward
/// from the node nearest the light (that node's plane in each axis has no upwind neighbour
/// along that axis; the node itself takes exp(-sigma_a tau |x - light|)). Occluder nodes are 0.
/// Rows of nodes on one anti-diagonal of the (j, k) plane are independent and run in parallel.
void solve_level0(const Level0Grid& grid, const Light& light, double sigma_a, std::vector<float>& rho,
                  std::vector<float>& scratch);

}  // namespace penumbra::render::lighting
