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
using test::light_volume;

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
