// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/occlusion/occlusion_lighting_gpu_test.cpp -- the in-situ light field of lighting model
// "occlusion" (render::OcclusionLighting, penumbra/render/occlusion.h) with its cones traced on the GPU, against the
// same object on the CPU: spaces "points" and "volume", occlusion times two coloured lights, two
// steps (the pyramid is re-uploaded) and two eyes (the mesh points are uploaded once).
//
// Tolerance: each factor agrees to ~1e-6 (gpu_cone_tracer_test.cpp explains why, and budgets 1e-4);
// the field is AO x (sum of two lights' colour x shadow), at most 2 in size, so 3e-4.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "cinema_database.h"
#include "config.h"
#include "context.h"
#include "penumbra/render/occlusion.h"
#include "occlusion_test_util.h"
#include "penumbra/render/gpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "test_util.h"  // tests/unit/insitu: TempDir, read_text

namespace penumbra::occlusion_test {
namespace {

TEST(OcclusionLightingGpu, LightFieldMatchesTheCpuInBothSpaces) {
  if (!gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  GpuOptions quiet;
  quiet.log = [](const std::string&) {};
  const auto device = GpuDevice::open(quiet);
  const auto mesh = tet_block(10, {0, 0, 0}, {2, 1, 1});
  const std::vector<Light> lights = {{Light::Kind::directional, {-1, 0.3, -0.5}, {1.0, 0.9, 0.8}},
                                     {Light::Kind::point, {2.5, 0.5, 1.5}, {0.3, 0.4, 0.6}}};
  for (render::OcclusionSpace space : {render::OcclusionSpace::points, render::OcclusionSpace::volume}) {
    render::OcclusionSettings config;
    config.grid_resolution = 32;
    config.volume_resolution = 12;
    config.space = space;
    render::OcclusionLighting cpu(mesh, config, lights), gpu(mesh, config, lights, device);
    double worst = 0, darkest = 3;
    for (double radius : {0.3, 0.45}) {  // two steps
      const auto scalars = field(*mesh, [&](const Vec3d& x) { return length(x - Vec3d{1.1, 0.5, 0.5}); });
      const TransferFunction tf = ball_tf(10.0, radius, 0.1);
      cpu.set_field(scalars, tf);
      gpu.set_field(scalars, tf);
      for (const Vec3d& eye : {Vec3d{-3, 2, 4}, Vec3d{5, -1, 0.5}}) {
        const std::vector<float> want = cpu.light_rgb(eye);
        const std::vector<float>& got = gpu.light_rgb(eye);
        ASSERT_EQ(got.size(), want.size());
        for (std::size_t i = 0; i < got.size(); ++i) {
          worst = std::max(worst, static_cast<double>(std::fabs(got[i] - want[i])));
          darkest = std::min(darkest, static_cast<double>(want[i]));
        }
      }
    }
    std::printf("[gpu-occlusion-lighting] space %s: max |GPU - CPU| = %.2e (darkest %.3f)\n",
                space == render::OcclusionSpace::points ? "points" : "volume", worst, darkest);
    EXPECT_LT(worst, 3e-4);
    EXPECT_LT(darkest, 0.2);  // the ball occludes and shadows: not a comparison of constants
  }
}

// End to end: a Context with backend "gpu" and lighting model "occlusion" traces its cones on the
// device and writes the image the CPU backend writes (within the GPU ray caster's own bound).
TEST(OcclusionLightingGpu, GpuBackendContextShadesLikeTheCpuBackend) {
  if (!gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  insitu::testing::TempDir tmp;
  const auto mesh = fixtures::block(fixtures::BlockCells::tets, 6, 6, 6, {0, 0, 0}, {1, 1, 1});
  const auto values = fixtures::sample(mesh, [](double x, double y, double z) {
    return std::sqrt((x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5) + (z - 0.6) * (z - 0.6));
  });
  for (const char* space : {"points", "volume"}) {
    std::string files[2];
    for (int b = 0; b < 2; ++b) {
      const std::string dir = tmp / (std::string(space) + (b ? "-gpu" : "-cpu"));
      insitu::Context ctx(insitu::parse_config(
          R"({"output": {"directory": ")" + dir + R"("}, "backend": ")" + (b ? "gpu" : "cpu") +
          R"(", "image": {"width": 24, "height": 20, "background": [0, 0, 0]},
          "cameras": {"phi": [-90], "theta": [20]}, "fields": [{"name": "T"}],
          "lighting": {"model": "occlusion", "phong": {"ambient": 1, "diffuse": 0, "specular": 0},
            "lights": [{"type": "directional", "direction": [1, 0, 0]}],
            "occlusion": {"grid": 16, "splits": 3, "space": ")" + space + R"(", "volume_resolution": 12}}})"));
      ctx.publish_mesh(mesh.view());
      ctx.publish_field(fixtures::point_field("T", values), false);
      EXPECT_TRUE(ctx.execute(0.0, 1));
      const auto rows = insitu::CinemaDatabase::parse_csv(insitu::testing::read_text(dir + "/data.csv"), "data.csv");
      ASSERT_EQ(rows.size(), 2u);
      files[b] = dir + "/" + rows[1].back();
    }
    int w = 0, h = 0;
    const auto a = read_png_rgb(files[0], w, h), g = read_png_rgb(files[1], w, h);
    const double rms = rms_difference_pct(a, g);
    std::printf("[gpu-occlusion-lighting] context space %s: image RMS difference GPU vs CPU backend %.3f%%\n", space, rms);
    EXPECT_LT(rms, 0.5);
    double mean = 0;
    for (unsigned char v : a) mean += v;
    EXPECT_GT(mean / static_cast<double>(a.size()), 5.0) << "the image is not black";
  }
}

}  // namespace
}  // namespace penumbra::occlusion_test
