// SPDX-License-Identifier: BSD-3-Clause
// A frame whose camera sees the whole mesh in front of it walks with per-frame screen-space
// projections (walk_geometry.h); a single traced ray always projects per ray. Both must give the
// same picture, and a frame with the eye inside the mesh must fall back to per-ray projection.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "scenes.h"

namespace penumbra {
namespace {

using fixtures::BlockCells;

render::TransferFunction banded_tf() {
  render::TransferFunction tf;
  tf.colors = {{-1.0, 0.1, 0.2, 0.9}, {0.0, 0.2, 0.9, 0.3}, {1.0, 1.0, 0.3, 0.1}};
  tf.opacities = {{-1.0, 1.5}, {-0.2, 0.0}, {0.3, 3.0}, {1.0, 0.7}};
  return tf;
}

// Largest difference between each pixel of a rendered frame and the ray traced through its
// centre on its own.
double max_difference_to_traced_rays(const fixtures::OwnedMesh& owned, const render::Camera& cam, int& covered) {
  const auto mesh = test::prepare(owned);
  render::CpuRayCaster caster(mesh);
  const auto field = fixtures::sample(owned, [](double x, double y, double z) {
    return std::sin(2.3 * x + 0.4) * std::cos(1.9 * y) + 0.5 * z - 0.3;
  });
  const std::vector<float> scalars(field.begin(), field.end());
  const auto tf = banded_tf();
  render::RenderOptions opts;
  opts.early_termination_opacity = 1.0;  // trace() never stops early
  const render::Image img = caster.render(scalars, tf, cam, opts);
  double worst = 0;
  covered = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const render::RayTrace r = caster.trace(scalars, tf, cam.primary_ray(x, y));
      covered += r.rgba[3] > 0.05;
      for (int c = 0; c < 4; ++c) worst = std::max(worst, std::fabs(img.pixel(x, y)[c] - r.rgba[c]));
    }
  return worst;
}

// Both paths walk the same tets and differ only in rounding (~1e-15 per segment); pixels are
// floats, so 3e-7 is float rounding of values up to ~2 plus margin. A wrong exit or a
// perspective error in the interpolation changes pixels by > 1e-3.
constexpr double kTolerance = 3e-7;

TEST(ScreenPath, MeshInFrontMatchesPerRayWalk) {
  const auto owned = fixtures::tet_block_with_hole(9);
  const auto mesh = test::prepare(owned);
  int covered = 0;
  // Oblique, and straight down the hole (rays through vertices, along edges and faces).
  for (const auto& cam : {render::Camera::orbit(mesh->bounds, 37, 28, 35, 40, 32),
                          render::Camera::look_at({0.5, 0.5, 3}, {0.5, 0.5, 0.5}, {0, 1, 0}, 30, 27, 27)}) {
    EXPECT_LT(max_difference_to_traced_rays(owned, cam, covered), kTolerance);
    EXPECT_GT(covered, 150);
  }
}

TEST(ScreenPath, TilesCrowdedWithSubPixelFacesMatchPerRayWalk) {
  // 8x8 pixels over 1152 boundary faces: a face smaller than a pixel is listed only in the tile
  // of a pixel centre its box holds, and none may be missed.
  const auto owned = fixtures::tet_block_with_hole(9);
  const auto mesh = test::prepare(owned);
  int covered = 0;
  EXPECT_LT(max_difference_to_traced_rays(owned, render::Camera::orbit(mesh->bounds, 37, 28, 35, 8, 8), covered),
            kTolerance);
  EXPECT_GT(covered, 10);
}

TEST(ScreenPath, TilesWhoseFacesAllCoverThePixelCentresUseTheBvh) {
  // A slab of 400 cells, each 1/400 thin in y, seen along x with the image turned by 45 degrees:
  // its end faces are thin strips lying diagonally across the picture, so the box of nearly
  // every one of them holds the middle pixel centres. Those tiles list more faces than a
  // search through the BVH costs, and the frame finds their entries through the BVH while still
  // walking in screen space.
  const auto owned = fixtures::block(BlockCells::tets, 1, 400, 1, {0, 0, 0}, {0.6, 1, 1});
  const double r = std::sqrt(0.5);
  const auto cam = render::Camera::look_at({-2.5, 0.52, 0.47}, {0.3, 0.5, 0.5}, {0, r, r}, 24, 8, 8);
  int covered = 0;
  EXPECT_LT(max_difference_to_traced_rays(owned, cam, covered), kTolerance);
  EXPECT_GT(covered, 30);
}

TEST(ScreenPath, PointNumberingDoesNotChangeThePicture) {
  // The caster renumbers the points for the walk; a mesh whose points come in another order
  // must give the same picture, lit (the light field is per mesh point id) and unlit.
  const auto owned = fixtures::tet_block_with_hole(7);
  fixtures::OwnedMesh shuffled = owned;
  const std::size_t np = owned.point_count();
  std::vector<std::int64_t> position(np);  // new id of each old point
  for (std::size_t i = 0; i < np; ++i) position[i] = static_cast<std::int64_t>((i * 7919) % np);
  ASSERT_EQ(std::gcd(std::size_t{7919}, np), 1u);
  for (std::size_t i = 0; i < np; ++i)
    for (int a = 0; a < 3; ++a) shuffled.xyz[3 * position[i] + a] = owned.xyz[3 * i + a];
  for (auto& id : shuffled.connectivity) id = position[static_cast<std::size_t>(id)];
  auto f = [](double x, double y, double z) { return std::sin(2.3 * x + 0.4) * std::cos(1.9 * y) + 0.5 * z - 0.3; };
  const auto a_values = fixtures::sample(owned, f), b_values = fixtures::sample(shuffled, f);
  const std::vector<float> a_scalars(a_values.begin(), a_values.end()), b_scalars(b_values.begin(), b_values.end());
  std::vector<float> a_light(3 * np), b_light(3 * np);
  for (std::size_t i = 0; i < np; ++i)
    for (int c = 0; c < 3; ++c)
      b_light[3 * position[i] + c] = a_light[3 * i + c] = static_cast<float>(0.3 + 0.2 * c + 0.5 * owned.xyz[3 * i]);
  const auto a_mesh = test::prepare(owned), b_mesh = test::prepare(shuffled);
  const render::CpuRayCaster a_caster(a_mesh), b_caster(b_mesh);
  // From outside (screen space) and from inside the bounds (per-ray projection).
  for (const auto& cam : {render::Camera::orbit(a_mesh->bounds, 37, 28, 35, 32, 32),
                          render::Camera::look_at({0.2, 0.15, 0.4}, {0.9, 0.8, 0.6}, {0, 0, 1}, 60, 24, 24)})
  for (const bool lit : {false, true}) {
    render::RenderOptions a_opts, b_opts;
    if (lit) {
      a_opts.shading.model = b_opts.shading.model = render::LightingModel::light_volume;
      a_opts.shading.light_rgb = &a_light;
      b_opts.shading.light_rgb = &b_light;
    }
    const render::Image a = a_caster.render(a_scalars, banded_tf(), cam, a_opts);
    const render::Image b = b_caster.render(b_scalars, banded_tf(), cam, b_opts);
    double worst = 0, alpha = 0;
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        alpha += a.pixel(x, y)[3];
        for (int c = 0; c < 4; ++c) worst = std::max(worst, std::fabs(double{a.pixel(x, y)[c]} - b.pixel(x, y)[c]));
      }
    EXPECT_LT(worst, kTolerance) << (lit ? "lit" : "unlit") << " " << cam.width;
    EXPECT_GT(alpha, 50.0);
  }
}

TEST(ScreenPath, HexMeshSplitIntoTetsMatchesPerRayWalk) {
  const auto owned = fixtures::block(BlockCells::hexes, 5, 4, 6, {-1, -1, -1}, {1, 0.5, 2});
  const auto mesh = test::prepare(owned);
  int covered = 0;
  EXPECT_LT(max_difference_to_traced_rays(owned, render::Camera::orbit(mesh->bounds, -63, 17, 30, 36, 36), covered),
            kTolerance);
  EXPECT_GT(covered, 150);
}

TEST(ScreenPath, EyeInsideTheMeshFallsBackToPerRayProjection) {
  // Half of the mesh lies behind the eye: screen coordinates do not exist for it.
  const auto owned = fixtures::block(BlockCells::tets, 6, 6, 6, {0, 0, 0}, {1, 1, 1});
  const auto cam = render::Camera::look_at({0.43, 0.51, 0.37}, {1.2, 0.8, 0.6}, {0, 0, 1}, 60, 24, 24);
  int covered = 0;
  EXPECT_LT(max_difference_to_traced_rays(owned, cam, covered), kTolerance);
  EXPECT_EQ(covered, cam.width * cam.height);
}

}  // namespace
}  // namespace penumbra
