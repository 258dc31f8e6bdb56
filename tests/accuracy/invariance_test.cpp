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

/// Float32 input coordinates: the mesh moved by up to 1e3 diagonals and only then rounded to
/// float32, as a solver in single precision would hand it over. The rounding moves the input's
/// points themselves by up to 3e-5 of the diagonal at 1e3 diagonals (half of float32's step
/// there), which no renderer can undo: both renderers draw the rounded points exactly, and the
/// measured change is 0.022 % RMS with no pixel off by more than one level, so the RMS bound here
/// is 0.03 % (the level bound is the invariance bound). Farther away float32 has lost the mesh.
constexpr double kFloat32InputRmsPct = 0.03;
void expect_float32_input_invariant(const std::string& name, const test::Renderer& render, test::Scene base) {
  auto to_float32 = [](fixtures::OwnedMesh& m) {
    for (double& v : m.xyz) v = static_cast<float>(v);
  };
  to_float32(base.mesh);
  const auto reference = render(test::prepare(base.mesh), base);
  const double diagonal = test::prepare(base.mesh)->bounds.diagonal();
  for (double d : {10.0, 100.0, 1000.0}) {
    test::Scene t = test::transformed(base, 1.0, Vec3d{0.6, -0.7, 0.4} * (d * diagonal));
    to_float32(t.mesh);
    const test::Difference diff = test::difference(render(test::prepare(t.mesh), t), reference);
    std::printf("[invariance] %s, float32 input, translate %g: rms %.4f %% of 255, max %d levels\n", name.c_str(), d,
                diff.rms_pct, diff.max_levels);
    EXPECT_LE(diff.rms_pct, kFloat32InputRmsPct) << name << ", translate " << d;
    EXPECT_LE(diff.max_levels, test::kMaxLevels) << name << ", translate " << d;
  }
}

TEST(Invariance, Float32InputCoordinatesMovedUpTo1e3Diagonals) {
  expect_float32_input_invariant("cpu, phong", render_cpu, hole_scene(render::LightingModel::phong));
  if (render::gpu_backend_compiled())
    expect_float32_input_invariant("gpu, phong", render_gpu, hole_scene(render::LightingModel::phong));
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
