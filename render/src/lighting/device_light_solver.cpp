// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/device_light_solver.cpp -- the light volume's kernels on a GPU
#include "device_light_solver.h"

#include <algorithm>

namespace penumbra::render::lighting {

// A light's device buffers, and whether its level-1 values there are older than the host's.
struct DeviceLightSolver::DeviceLight final : SolverLightData {
  explicit DeviceLight(std::shared_ptr<GpuLightBuffers> b) : buffers(std::move(b)) {}
  std::shared_ptr<GpuLightBuffers> buffers;
  bool rho1_stale = true;
};

DeviceLightSolver::DeviceLightSolver(std::shared_ptr<GpuDevice> device, const TetMesh& mesh,
                                     const Level1Topology& topology, const std::vector<float>& scatter_weights,
                                     const std::vector<Bounds>& occluders)
    : m_kernels(std::move(device), mesh, topology, scatter_weights, occluders) {}

DeviceLightSolver::DeviceLight& DeviceLightSolver::device_light(LightState& l) {
  if (!l.solver_data) l.solver_data = std::make_unique<DeviceLight>(m_kernels.new_light());
  return static_cast<DeviceLight&>(*l.solver_data);
}

void DeviceLightSolver::solve_level0(LightState& l, const Level0Grid&, double sigma_a, std::vector<float>& rho0) {
  DeviceLight& device = device_light(l);
  m_kernels.solve_level0(*device.buffers, l.light, sigma_a, rho0);
  device.rho1_stale = true;  // the light's level 1 starts over on the host (LightState::take_level0)
}

void DeviceLightSolver::prepare_order(LightState& l, const Level1Context& ctx) {
  // The device keeps no walks, so none are recorded.
  if (l.ensure_order(ctx, false)) m_kernels.set_order(*device_light(l).buffers, l.order);
}

Level1Piece DeviceLightSolver::level1_pass(LightState& l, const Level1Context& ctx, Clock::time_point) {
  std::size_t lost = 0;
  m_pass_ms = timed_ms([&] {
    prepare_order(l, ctx);
    DeviceLight& device = device_light(l);
    if (device.rho1_stale) m_kernels.set_rho1(*device.buffers, l.rho1);
    device.rho1_stale = false;
    l.pass_state.residual = m_kernels.level1_pass(*device.buffers, l.light, ctx, l.rho1, lost);
  });
  return {true, lost, nullptr};
}

ScatterPiece DeviceLightSolver::scatter_piece(const LightSchedule& schedule, LightCombination& light,
                                              const ScatterRequest& request) {
  const double tolerance = light.scatter_tolerance(request.relative_tolerance);
  if (!schedule.allows(m_batch_ms)) return {};
  ScatterPiece piece{true, 0, request.residual};
  m_batch_ms = timed_ms([&] {
    if (m_source_stale) m_kernels.set_scatter_source(light.source(), light.colour());
    m_source_stale = false;
    // A batch of iterations, never more than the cap or the work units left.
    const int most = std::min(request.iterations_left, schedule.units_left());
    piece.iterations = m_kernels.scatter(most, tolerance, request.sigma_s, piece.residual);
  });
  return piece;
}

}  // namespace penumbra::render::lighting
