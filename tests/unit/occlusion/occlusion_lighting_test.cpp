// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/occlusion/occlusion_lighting_test.cpp -- the in-situ light field of lighting model
// "occlusion" (render::OcclusionLighting, penumbra/render/occlusion.h) on the CPU against the exact shadow
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "config.h"
#include "penumbra/render/occlusion.h"
#include "occlusion_test_util.h"

namespace penumbra::occlusion_test {
namespace {

TEST(OcclusionLighting, ShadowsIncludeTheMediumNextToThePoint) {
  // A uniform block lit from +z, seen from far below: at the points of the bottom face the
  // occlusion cone leaves the block at once (AO = 1) and the light crosses the whole block,
  // exp(-tau) = 0.135. A shadow cone that skipped its gap of 3 sigma0 (3 / 31 here) would give
  // exp(-tau (1 - 3 / 31)) = 0.164; every space must be within 3 % of exact.
  const auto mesh = tet_block(8, {0, 0, 0}, {1, 1, 1});
  const double tau = 2.0;
  const std::vector<Light> lights = {{Light::Kind::directional, {0, 0, -1}, {1, 1, 1}}};
  const auto scalars = field(*mesh, [](const Vec3d&) { return 0.0; });
  for (render::OcclusionSpace space : {render::OcclusionSpace::points, render::OcclusionSpace::volume,
                                       render::OcclusionSpace::image}) {
    render::OcclusionSettings config;
    config.grid_resolution = 32;
    config.volume_resolution = 16;
    config.space = space;
    render::OcclusionLighting lighting(mesh, config, lights);
    lighting.set_field(scalars, constant_tf(tau));
    const Vec3d eye{0.5, 0.5, -100};
    const std::vector<float>& rgb = lighting.light_rgb(eye);
    const auto at = lighting.light_at(eye);
    double worst = 0;
    int n = 0;
    for (std::size_t p = 0; p < mesh->points.size(); ++p) {
      const Vec3d& x = mesh->points[p];
      if (x.z != 0.0 || x.x < 0.2 || x.x > 0.8 || x.y < 0.2 || x.y > 0.8) continue;
      double v = rgb[3 * p];
      if (space == render::OcclusionSpace::image) {
        double c[3];
        at(x, c);
        v = c[0];
      }
      worst = std::max(worst, std::fabs(v / std::exp(-tau) - 1.0));
      ++n;
    }
    std::printf("uniform block lit through its whole depth, space %d: %d points, worst relative error %.4f\n",
                static_cast<int>(space), n, worst);
    ASSERT_GT(n, 8);
    EXPECT_LT(worst, 0.03) << static_cast<int>(space);
  }
}

}  // namespace
}  // namespace penumbra::occlusion_test
