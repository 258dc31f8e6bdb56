// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/lighting/light_moving_mesh_test.cpp -- the light volume of a mesh whose points move
// (LightVolume::move_points): warm start, convergence like a moved light, the rebuilt volume's light
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "penumbra/core/error.h"
#include "lighting_test_util.h"
#include "penumbra/render/gpu_ray_caster.h"

namespace penumbra::lighting_test {
namespace {

// A hex block (split into tets) and the same block a step of a vortex later.
struct MovingBlock {
  fixtures::OwnedMesh before_cells = fixtures::block(fixtures::BlockCells::hexes, 10, 10, 8, {0, 0, 0}, {1, 1, 1});
  fixtures::OwnedMesh after_cells = [this] {
    auto m = before_cells;
    fixtures::swirl(m, {0.5, 0.5, 0}, 0.6, 0.08);
    return m;
  }();
  std::shared_ptr<const TetMesh> before = prepare(before_cells);
  std::shared_ptr<const TetMesh> after =
      std::make_shared<const TetMesh>(render::move_tet_mesh(*before, after_cells.view()));
  std::vector<float> scalars = field(*before, [](const Vec3d& p) { return 0.5 + 0.5 * std::sin(5 * p.x + 2 * p.z); });
  LightVolumeOptions options = [] {
    LightVolumeOptions o;
    o.level0_resolution = 16;
    o.sigma_s = {0.5, 0.5, 0.5};
    return o;
  }();
  Light light = directional({1, 0.4, -0.6});
};

// Frames until converged at `budget`, at most `cap`.
int frames_to_converge(LightVolume& lv, const render::LightBudget& budget, int cap = 1000) {
  for (int f = 1; f <= cap; ++f)
    if (lv.update(budget).converged) return f;
  return cap + 1;
}

double max_difference(const std::vector<float>& a, const std::vector<float>& b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::fabs(double(a[i]) - b[i]));
  return worst;
}

void run_moving_light_checks(const std::shared_ptr<render::GpuDevice>& device) {
  MovingBlock s;
  s.options.device = device;
  render::LightBudget budget;
  budget.max_work_units = 1;

  // The mesh moves under a converged light...
  LightVolume moving(s.before, s.options);
  moving.set_field(s.scalars, ramp_tf(3.0));
  moving.set_lights({s.light});
  ASSERT_TRUE(moving.update().converged);
  const std::vector<float> light_before = moving.light_rgb();
  moving.move_points(s.after);
  const int moving_frames = frames_to_converge(moving, budget);

  // ... the light moves on a mesh that stays (the same budget)...
  LightVolume turned(s.before, s.options);
  turned.set_field(s.scalars, ramp_tf(3.0));
  turned.set_lights({s.light});
  ASSERT_TRUE(turned.update().converged);
  turned.set_lights({directional({1, 0.45, -0.6})});
  const int turned_frames = frames_to_converge(turned, budget);

  // ... and a volume made for the moved mesh starts cold.
  LightVolume rebuilt(s.after, s.options);
  rebuilt.set_field(s.scalars, ramp_tf(3.0));
  rebuilt.set_lights({s.light});
  const int cold_frames = frames_to_converge(rebuilt, budget);

  std::printf("frames to converge at one work unit: moved mesh %d, moved light %d, new volume %d\n", moving_frames,
              turned_frames, cold_frames);
  EXPECT_LE(moving_frames, turned_frames);
  EXPECT_LT(moving_frames, cold_frames);
  // Converged, the two volumes agree within a few propagation tolerances (each pass stops when no
  // vertex changes by more than 1/40 of an 8-bit level; the scattering to 1e-4 of the light).
  EXPECT_LE(max_difference(moving.light_rgb(), rebuilt.light_rgb()), 1.0 / 255);
  // The motion changed the light: the moved volume did not keep the old one.
  EXPECT_GT(max_difference(moving.light_rgb(), light_before), 4.0 / 255);
}

TEST(LightMovingMesh, ContinuesLikeAMovedLightAndEndsAtTheRebuiltVolumesLight) { run_moving_light_checks(nullptr); }

TEST(LightMovingMesh, OnTheGpuToo) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  render::GpuOptions quiet;
  quiet.log = [](const std::string&) {};
  run_moving_light_checks(render::GpuDevice::open(quiet));
}

TEST(LightMovingMesh, AnotherMeshIsRefused) {
  MovingBlock s;
  LightVolume lv(s.before, s.options);
  EXPECT_THROW(lv.move_points(nullptr), Error);
  EXPECT_THROW(lv.move_points(tet_block(3, 3, 3, {0, 0, 0}, {1, 1, 1})), Error);
}

}  // namespace
}  // namespace penumbra::lighting_test
