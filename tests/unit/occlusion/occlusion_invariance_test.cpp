// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/occlusion/occlusion_invariance_test.cpp -- the in-situ occlusion lighting (ambient
// occlusion times shadowed lights, render::OcclusionLighting, penumbra/render/occlusion.h) gives the same picture at any
// scale and position of the mesh: spaces "points" and "volume" on the CPU and the GPU, "image" on
// the CPU (tests/accuracy/invariance.h has the transformations and the bound).
#include "occlusion_renderer.h"

namespace penumbra {
namespace {

TEST(OcclusionInvariance, CpuPointsSpace) {
  test::expect_invariant("cpu, occlusion points", test::occlusion(false, render::OcclusionSpace::points),
                         test::hole_scene(render::LightingModel::none));
}

TEST(OcclusionInvariance, CpuVolumeSpace) {
  test::expect_invariant("cpu, occlusion volume", test::occlusion(false, render::OcclusionSpace::volume),
                         test::hole_scene(render::LightingModel::none));
}

TEST(OcclusionInvariance, CpuImageSpace) {
  test::expect_invariant("cpu, occlusion image", test::occlusion(false, render::OcclusionSpace::image),
                         test::hole_scene(render::LightingModel::none));
}

TEST(OcclusionInvariance, GpuPointsSpace) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  test::expect_invariant("gpu, occlusion points", test::occlusion(true, render::OcclusionSpace::points),
                         test::hole_scene(render::LightingModel::none));
}

TEST(OcclusionInvariance, GpuVolumeSpace) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  test::expect_invariant("gpu, occlusion volume", test::occlusion(true, render::OcclusionSpace::volume),
                         test::hole_scene(render::LightingModel::none));
}

}  // namespace
}  // namespace penumbra
