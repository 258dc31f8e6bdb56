// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/occlusion/occlusion_invariance_test.cpp -- the in-situ occlusion lighting (ambient
// occlusion times shadowed lights, insitu/src/occlusion_lighting.h) gives the same picture at any
// scale and position of the mesh: spaces "points" and "volume" on the CPU and the GPU, "image" on
// the CPU (tests/accuracy/invariance.h has the transformations and the bound).
#include "invariance.h"
#include "occlusion_lighting.h"

namespace penumbra {
namespace {

/// Occlusion towards the camera's eye and shadows towards the scene's lights, in `space`, with
/// cones traced on the GPU device or the CPU; the frame ray cast by the caster of that backend.
test::Renderer occlusion(bool gpu, insitu::OcclusionSpace space) {
  return [=](const std::shared_ptr<const render::TetMesh>& mesh, const test::Scene& s) {
    insitu::OcclusionConfig config;
    config.grid_resolution = 32;
    config.volume_resolution = 16;
    config.space = space;
    insitu::OcclusionLighting lighting(mesh, config, s.lights, gpu ? test::device() : nullptr);
    lighting.set_field(s.scalars, s.tf);
    test::Scene lit = s;
    lit.options.shading.model = render::LightingModel::light_volume;
    if (space == insitu::OcclusionSpace::image) {
      lit.options.shading.light_at = lighting.light_at(s.camera.eye);
      return test::render_cpu(mesh, lit);
    }
    lit.options.shading.light_rgb = &lighting.light_rgb(s.camera.eye);
    return gpu ? test::render_gpu(mesh, lit) : test::render_cpu(mesh, lit);
  };
}

TEST(OcclusionInvariance, CpuPointsSpace) {
  test::expect_invariant("cpu, occlusion points", occlusion(false, insitu::OcclusionSpace::points),
                         test::hole_scene(render::LightingModel::none));
}

TEST(OcclusionInvariance, CpuVolumeSpace) {
  test::expect_invariant("cpu, occlusion volume", occlusion(false, insitu::OcclusionSpace::volume),
                         test::hole_scene(render::LightingModel::none));
}

TEST(OcclusionInvariance, CpuImageSpace) {
  test::expect_invariant("cpu, occlusion image", occlusion(false, insitu::OcclusionSpace::image),
                         test::hole_scene(render::LightingModel::none));
}

TEST(OcclusionInvariance, GpuPointsSpace) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  test::expect_invariant("gpu, occlusion points", occlusion(true, insitu::OcclusionSpace::points),
                         test::hole_scene(render::LightingModel::none));
}

TEST(OcclusionInvariance, GpuVolumeSpace) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  test::expect_invariant("gpu, occlusion volume", occlusion(true, insitu::OcclusionSpace::volume),
                         test::hole_scene(render::LightingModel::none));
}

}  // namespace
}  // namespace penumbra
