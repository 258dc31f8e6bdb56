// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/rank_scattering_test.cpp -- the scattering solved over ranks (RankScattering)
// on one rank against the light volume's own scattering of the same light
#include <gtest/gtest.h>

#include <cmath>

#include "fixtures/meshes.h"
#include "penumbra/render/light_volume.h"
#include "rank_scattering.h"

namespace penumbra::insitu {
namespace {

TEST(RankScattering, OneRankSolvesTheLightVolumesScattering) {
  const auto mesh = std::make_shared<const render::TetMesh>(render::prepare_tet_mesh(
      fixtures::block(fixtures::BlockCells::tets, 9, 8, 7, {0, 0, 0}, {1, 0.9, 0.8}).view()));
  std::vector<float> s(mesh->points.size());
  for (std::size_t p = 0; p < s.size(); ++p) s[p] = static_cast<float>(std::exp(-4 * dot(mesh->points[p] - Vec3d{0.5, 0.4, 0.4}, mesh->points[p] - Vec3d{0.5, 0.4, 0.4})));
  render::TransferFunction tf;
  tf.colors = {{0, 1, 1, 1}};
  tf.opacities = {{0, 0}, {1, 6}};
  const std::array<double, 3> sigma_s{0.5, 1.0, 2.0};
  auto solved = [&](std::array<double, 3> scattering) {
    render::LightVolumeOptions o;
    o.level0_resolution = 16;
    o.sigma_s = scattering;
    o.scatter_tolerance = 1e-6;
    render::LightVolume lv(mesh, o);
    lv.set_lights({{render::Light::Kind::directional, {1, 0.3, -0.5}, {1, 0.8, 0.6}}});
    lv.set_field(s, tf);
    EXPECT_TRUE(lv.update().converged);
    return lv.light_rgb();
  };
  const std::vector<float> expected = solved(sigma_s), source = solved({0, 0, 0});
  const auto group = serial_group();
  const SharedPoints shared(*group, *mesh, {});
  const RankScattering scattering(*group, *mesh, shared);
  std::vector<float> light;
  const RankScattering::Report r = scattering.solve(*group, source, sigma_s, 1e-6, 2000, light);
  EXPECT_TRUE(r.converged);
  EXPECT_GT(r.iterations, 3);
  double worst = 0, change = 0;
  for (std::size_t i = 0; i < light.size(); ++i) {
    worst = std::max(worst, std::fabs(double(light[i]) - expected[i]));
    change = std::max(change, std::fabs(double(source[i]) - expected[i]));
  }
  EXPECT_LT(worst, 1e-4);   // the same system solved to 1e-6 of the largest light
  EXPECT_GT(change, 1e-2);  // and the scattering changed the light (the check can fail)
  // A warm start from the solution stops at once.
  EXPECT_LE(scattering.solve(*group, source, sigma_s, 1e-6, 2000, light).iterations, 2);
}

}  // namespace
}  // namespace penumbra::insitu
