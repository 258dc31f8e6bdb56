// SPDX-License-Identifier: BSD-3-Clause
// tests/accuracy/nonconforming_test.cpp -- meshes with hanging nodes (T-junctions)
#include <gtest/gtest.h>

#include <random>

#include "penumbra/render/boundary_surface.h"
#include "scenes.h"

using namespace penumbra;

namespace {

// One hex [0,1]^3 beside a 2x2x2 block of hexes [1,2]x[0,1]^2: the coarse face at x = 1 meets
// four fine faces and a hanging node, so no face there is matched. Both sides are split into
// tets, and every face on x = 1 stays an unmatched (boundary) face.
fixtures::OwnedMesh hanging_node_mesh() {
  auto coarse = fixtures::block(fixtures::BlockCells::hexes, 1, 1, 1, {0, 0, 0}, {1, 1, 1});
  const auto fine = fixtures::block(fixtures::BlockCells::hexes, 2, 2, 2, {1, 0, 0}, {2, 1, 1});
  const auto base = static_cast<std::int64_t>(coarse.point_count());
  coarse.xyz.insert(coarse.xyz.end(), fine.xyz.begin(), fine.xyz.end());
  for (std::size_t c = 0; c < fine.cell_count(); ++c) {
    const auto* v = &fine.connectivity[8 * c];
    coarse.add_cell(12, {v[0] + base, v[1] + base, v[2] + base, v[3] + base, v[4] + base, v[5] + base, v[6] + base,
                         v[7] + base});
  }
  return coarse;
}

}  // namespace

TEST(NonConformingMesh, RaysCrossTheHangingNodeInterfaceWithoutLoss) {
  const auto mesh = test::prepare(hanging_node_mesh());
  ASSERT_FALSE(mesh->surface->is_closed());  // the x = 1 interface is unmatched
  render::CpuRayCaster caster(mesh);
  const std::vector<float> scalars(mesh->points.size(), 0.0f);
  const double sigma = 0.7;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.05, 0.95);
  for (int i = 0; i < 200; ++i) {
    // Rays from x < 0 through the box, crossing x = 1 at random heights and angles.
    const Vec3d o{-1.0, u(rng), u(rng)};
    const Vec3d target{3.0, u(rng), u(rng)};
    const Vec3d d = normalize(target - o);
    const double len = test::chord({0, 0, 0}, {2, 1, 1}, o, d);
    const auto tr = caster.trace(scalars, test::constant_tf(sigma), {o, d});
    // Tolerance: the re-entry slack admits at most 1e-9 of the diagonal per crossing.
    EXPECT_NEAR(tr.length_inside, len, 1e-8) << "ray " << i;
    EXPECT_NEAR(tr.optical_depth, sigma * len, 1e-8) << "ray " << i;
  }
}

TEST(NonConformingMesh, ImageMatchesReference) {
  const auto mesh = test::prepare(hanging_node_mesh());
  render::CpuRayCaster caster(mesh);
  const auto field = fixtures::sample(hanging_node_mesh(), [](double x, double y, double z) { return x + y * z; });
  const auto scalars = test::to_float(field);
  render::TransferFunction tf;
  tf.colors = {{0.0, 0.1, 0.2, 0.9}, {3.0, 1.0, 0.4, 0.1}};
  tf.opacities = {{0.0, 0.5}, {3.0, 3.0}};
  const auto cam = render::Camera::orbit(mesh->bounds, 10, 15, 30, 96, 96);
  const float bg[3] = {1, 1, 1};
  const auto fast = render::to_rgb8(caster.render(scalars, tf, cam, {1.0}), bg);
  const auto ref = render::to_rgb8(render::render_reference(*mesh, scalars, tf, cam), bg);
  // The two integrate the same segments to ~1e-9; 8-bit rounding is all that may differ.
  EXPECT_LT(render::rms_difference_pct(fast, ref), 0.1);
}
