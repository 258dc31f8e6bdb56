// SPDX-License-Identifier: BSD-3-Clause
// tests/accuracy/invariance_test.cpp -- the same picture at any scale and position of the mesh,
// on the CPU and GPU ray casters, unlit, with Phong shading and with the light volume
#include "invariance.h"

namespace penumbra {
namespace {

using test::expect_invariant;
using test::hole_scene;
using test::render_cpu;
using test::render_gpu;

/// The light volume of the scene's lights solved to convergence (on the CPU, or on the GPU
/// device), then the frame ray cast with its light field by the caster of the same backend.
test::Renderer light_volume(bool gpu, render::LightSolveMode mode, double scattering) {
  return [=](const std::shared_ptr<const render::TetMesh>& mesh, const test::Scene& s) {
    render::LightVolumeOptions o;
    o.level0_resolution = 24;
    o.mode = mode;
    o.sigma_s = {scattering, 0.5 * scattering, 0.25 * scattering};
    if (gpu) o.device = test::device();
    render::LightVolume volume(mesh, o);
    volume.set_lights(s.lights);
    volume.set_field(s.scalars, s.tf);
    EXPECT_TRUE(volume.update().converged);
    test::Scene lit = s;
    lit.options.shading.model = render::LightingModel::light_volume;
    lit.options.shading.light_rgb = &volume.light_rgb();
    return gpu ? render_gpu(mesh, lit) : render_cpu(mesh, lit);
  };
}

TEST(Invariance, CpuRayCasterUnlit) { expect_invariant("cpu, unlit", render_cpu, hole_scene(render::LightingModel::none)); }

TEST(Invariance, CpuRayCasterPhong) { expect_invariant("cpu, phong", render_cpu, hole_scene(render::LightingModel::phong)); }

TEST(Invariance, GpuRayCasterUnlit) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  expect_invariant("gpu, unlit", render_gpu, hole_scene(render::LightingModel::none));
}

TEST(Invariance, GpuRayCasterPhong) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  expect_invariant("gpu, phong", render_gpu, hole_scene(render::LightingModel::phong));
}

TEST(Invariance, CpuLightVolumeTwoLevelsWithScattering) {
  expect_invariant("cpu, light volume", light_volume(false, render::LightSolveMode::two_level, 0.6),
                   hole_scene(render::LightingModel::none));
}

TEST(Invariance, CpuLightVolumeLevel0Only) {
  expect_invariant("cpu, light volume level 0", light_volume(false, render::LightSolveMode::level0_only, 0),
                   hole_scene(render::LightingModel::none));
}

TEST(Invariance, GpuLightVolumeTwoLevelsWithScattering) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  expect_invariant("gpu, light volume", light_volume(true, render::LightSolveMode::two_level, 0.6),
                   hole_scene(render::LightingModel::none));
}

TEST(Invariance, GpuLightVolumeLevel0Only) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  expect_invariant("gpu, light volume level 0", light_volume(true, render::LightSolveMode::level0_only, 0),
                   hole_scene(render::LightingModel::none));
}

}  // namespace
}  // namespace penumbra
