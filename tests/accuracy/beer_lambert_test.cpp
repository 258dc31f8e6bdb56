// SPDX-License-Identifier: BSD-3-Clause
// Homogeneous tet blocks against Beer-Lambert's closed form.
#include <gtest/gtest.h>

#include "scenes.h"

namespace penumbra {
namespace {

using fixtures::BlockCells;

TEST(BeerLambert, RaysThroughHomogeneousBlockMatchClosedForm) {
  const Vec3d lo{0, 0, 0}, hi{2, 1, 1.5};
  const auto mesh = test::prepare(fixtures::block(BlockCells::tets, 7, 5, 6, lo, hi));
  render::CpuRayCaster caster(mesh);
  const std::vector<float> scalars(mesh->points.size(), 0.3f);
  const Vec3d origins[] = {{-1, 0.31, 0.77}, {3, -0.5, 2}, {0.9, 0.45, -2}};
  const Vec3d targets[] = {{2.5, 0.62, 0.41}, {-0.2, 1.2, -0.3}, {1.1, 0.5, 3}};
  for (double sigma : {0.01, 0.1, 1.0, 5.0, 50.0})
    for (int i = 0; i < 3; ++i) {
      const Vec3d d = normalize(targets[i] - origins[i]);
      const double len = test::chord(lo, hi, origins[i], d);
      ASSERT_GT(len, 0.1);
      const render::RayTrace r = caster.trace(scalars, test::constant_tf(sigma), {origins[i], d});
      // The walk sums per-segment depths, each exact up to rounding (~1e-16 relative per
      // segment, a few dozen segments): 1e-12 relative leaves a wide margin yet catches any
      // lost or doubled segment, which would change the depth by > 1e-3.
      EXPECT_NEAR(r.optical_depth, sigma * len, 1e-12 * sigma * len) << "sigma=" << sigma << " ray " << i;
      EXPECT_NEAR(r.length_inside, len, 1e-12) << "ray " << i;
      const double t = std::exp(-sigma * len);
      // Opacity 1 - T and white emission C = 1 - T exactly for a constant medium; the products of
      // per-segment transmittances carry the same ~1e-15 rounding.
      EXPECT_NEAR(r.rgba[3], 1.0 - t, 1e-12) << "sigma=" << sigma;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.rgba[c], 1.0 - t, 1e-12) << "sigma=" << sigma;
      EXPECT_EQ(r.entries, 1);
    }
}

TEST(BeerLambert, RenderedImageMatchesClosedFormPerPixel) {
  const Vec3d lo{-1, -1, -1}, hi{1, 1, 1};
  const auto mesh = test::prepare(fixtures::block(BlockCells::tets, 6, 6, 6, lo, hi));
  render::CpuRayCaster caster(mesh);
  const std::vector<float> scalars(mesh->points.size(), 1.0f);
  const double sigma = 0.8;
  const auto cam = render::Camera::orbit(mesh->bounds, 27, 18, 30, 48, 40);
  render::RenderOptions opts;
  opts.early_termination_opacity = 1.0;  // compare the full integral
  const render::Image img = caster.render(scalars, test::constant_tf(sigma), cam, opts);
  int inside = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const render::Ray ray = cam.primary_ray(x, y);
      const double len = test::chord(lo, hi, ray.origin, ray.direction);
      inside += len > 0;
      // Pixels are stored as float: 1e-6 covers their rounding (6e-8) with margin.
      EXPECT_NEAR(img.pixel(x, y)[3], 1.0 - std::exp(-sigma * len), 1e-6) << x << "," << y;
    }
  EXPECT_GT(inside, cam.width * cam.height / 4);
}

TEST(BeerLambert, EyeInsideTheMeshIntegratesOnlyInFront) {
  const Vec3d lo{0, 0, 0}, hi{1, 1, 1};
  const auto mesh = test::prepare(fixtures::block(BlockCells::tets, 5, 5, 5, lo, hi));
  render::CpuRayCaster caster(mesh);
  const std::vector<float> scalars(mesh->points.size(), 0.0f);
  const Vec3d o{0.43, 0.51, 0.37}, d = normalize(Vec3d{1, 0.3, 0.2});
  const double len = test::chord(lo, hi, o, d);  // from the eye to the exit
  const auto r = caster.trace(scalars, test::constant_tf(2.0), {o, d});
  // The walk starts at the entry behind the eye and counts only t >= 0; same 1e-12 as above.
  EXPECT_NEAR(r.length_inside, len, 1e-12);
  EXPECT_NEAR(r.optical_depth, 2.0 * len, 1e-12);
  const auto ref = render::trace_reference(*mesh, scalars, test::constant_tf(2.0), {o, d});
  EXPECT_NEAR(ref.length_inside, len, 1e-12);
}

TEST(BeerLambert, EarlyTerminationStopsAtThreshold) {
  const Vec3d lo{0, 0, 0}, hi{1, 1, 1};
  const auto mesh = test::prepare(fixtures::block(BlockCells::tets, 8, 8, 8, lo, hi));
  render::CpuRayCaster caster(mesh);
  const std::vector<float> scalars(mesh->points.size(), 0.0f);
  const auto cam = render::Camera::look_at({0.5, 0.5, 3}, {0.5, 0.5, 0.5}, {0, 1, 0}, 10, 8, 8);
  render::RenderOptions opts;
  opts.early_termination_opacity = 0.9;
  // sigma = 20 over a unit chord: full opacity would be 1 - exp(-20); the walk stops at the
  // first tet boundary past 0.9, which is below 0.9 + one tet's worth (< 1 - exp(-20 * 0.25)).
  const render::Image img = caster.render(scalars, test::constant_tf(20.0), cam, opts);
  const float a = img.pixel(4, 4)[3];
  EXPECT_GE(a, 0.9f);
  EXPECT_LT(a, 1.0f - 1e-6f);
}

}  // namespace
}  // namespace penumbra
