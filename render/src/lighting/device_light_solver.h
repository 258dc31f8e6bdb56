// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/device_light_solver.h -- the light volume's kernels on a GPU
#pragma once
#include <memory>
#include <vector>

#include "gpu_light_solver.h"
#include "light_solver.h"

namespace penumbra::render::lighting {

/// The light volume solved by the compute shaders of GpuLightSolver, in float32. The host's
/// arrays stay the solution of record: what the volume changes there (a light's warm start) is
/// uploaded before the next pass, and every result is read back, so light_rho, level0_rho and
/// light_rgb mean what they mean on the CPU. A device pass cannot stop at a deadline, so its
/// pieces are whole passes and batches of scattering iterations.
class DeviceLightSolver final : public LightSolver {
public:
  /// Throws as GpuLightSolver's constructor does.
  DeviceLightSolver(std::shared_ptr<GpuDevice> device, const TetMesh& mesh, const Level1Topology& topology,
                    const std::vector<float>& scatter_weights, const std::vector<Bounds>& occluders);

  void move_points(const TetMesh& mesh, const Level1Topology& topology, const std::vector<float>& scatter_weights) override {
    m_kernels.move_points(mesh, topology, scatter_weights);
    m_source_stale = true;
  }
  void set_grid(const Level0Grid& grid) override { m_kernels.set_grid(grid); }
  void set_field(const Level0Grid& grid, const Level1Field& field) override { m_kernels.set_field(grid, field); }
  void solve_level0(LightState& l, const Level0Grid& grid, double sigma_a, std::vector<float>& rho0) override;
  bool orders_apart() const override { return false; }
  void prepare_order(LightState& l, const Level1Context& ctx) override;
  double expected_level1_ms(const LightState&) const override { return m_pass_ms; }
  Level1Piece level1_pass(LightState& l, const Level1Context& ctx, Clock::time_point deadline) override;
  void restart_scattering() override { m_source_stale = true; }
  ScatterPiece scatter_piece(const LightSchedule& schedule, LightCombination& light,
                             const ScatterRequest& request) override;
  double expected_read_back_ms() const override { return 0.0; }
  void read_scattering(std::vector<float>& colour) override { m_kernels.read_scatter(colour); }

private:
  struct DeviceLight;
  DeviceLight& device_light(LightState& l);

  GpuLightSolver m_kernels;
  bool m_source_stale = true;  // the device's scattering source is out of date
  // The last durations (ms; < 0: never timed): a level-1 pass, a batch of scattering iterations.
  double m_pass_ms = -1, m_batch_ms = -1;
};

}  // namespace penumbra::render::lighting
