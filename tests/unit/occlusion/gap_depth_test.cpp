// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/occlusion/gap_depth_test.cpp -- exact depth over a shadow cone's gap, and shadows
// that include it
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "occlusion_test_util.h"
#include "penumbra/core/error.h"

namespace penumbra::occlusion_test {
namespace {

TEST(GapDepth, HomogeneousBlockGivesTauTimesTheLengthInside) {
  const auto mesh = tet_block(6, {0, 0, 0}, {1, 1, 1});
  GapDepth gap(mesh);
  EXPECT_EQ(gap.depth({0.5, 0.5, 0.5}, {1, 0, 0}, 0.2), 0.0);  // no field bound yet
  gap.set_field(field(*mesh, [](const Vec3d&) { return 0.0; }), constant_tf(3.0));
  // Oblique, wholly inside: the direction's length does not matter.
  EXPECT_NEAR(gap.depth({0.41, 0.37, 0.52}, {2, -1, 0.5}, 0.2), 0.6, 1e-12);
  // Along a line of mesh edges (nodes at k / 6, so y = z = 1/3 is one) and through vertices:
  // every piece counted once.
  EXPECT_NEAR(gap.depth({0.05, 1.0 / 3, 1.0 / 3}, {1, 0, 0}, 0.5), 1.5, 1e-12);
  EXPECT_NEAR(gap.depth({1.0 / 6, 1.0 / 6, 1.0 / 6}, {1, 1, 1}, 0.3), 0.9, 1e-12);
  // Leaving the block: only the part inside counts.
  EXPECT_NEAR(gap.depth({0.9, 0.5, 0.5}, {1, 0, 0}, 0.5), 0.3, 1e-12);
  // From a boundary vertex outward, and wholly outside: nothing.
  EXPECT_EQ(gap.depth({1, 1, 1}, {1, 0.5, 0.2}, 0.3), 0.0);
  EXPECT_EQ(gap.depth({2, 2, 2}, {1, 0, 0}, 0.3), 0.0);
  // Degenerate requests.
  EXPECT_EQ(gap.depth({0.5, 0.5, 0.5}, {0, 0, 0}, 0.3), 0.0);
  EXPECT_EQ(gap.depth({0.5, 0.5, 0.5}, {1, 0, 0}, 0.0), 0.0);
  EXPECT_EQ(gap.depth({0.5, 0.5, 0.5}, {1, 0, 0}, -1.0), 0.0);
  EXPECT_EQ(gap.depth({0.5, 0.5, 0.5}, {std::numeric_limits<double>::quiet_NaN(), 0, 0}, 0.3), 0.0);
  EXPECT_EQ(gap.depth({std::numeric_limits<double>::quiet_NaN(), 0.5, 0.5}, {1, 0, 0}, 0.3), 0.0);
  // An unbounded segment stops where the mesh does.
  EXPECT_NEAR(gap.depth({0.5, 0.5, 0.5}, {0, 0, 1}, std::numeric_limits<double>::infinity()), 1.5, 1e-12);
}

TEST(GapDepth, LinearFieldThroughAPiecewiseLinearTransferFunctionIsIntegratedExactly) {
  // s = x; tau(s) = 4 s on [0, 0.5] and 2 + 8 (s - 0.5) on [0.5, 1] (a kink at 0.5, not on a mesh
  // node). From x = 0.2 to 0.9: 2 (0.25 - 0.04) + 2 * 0.4 + 4 * 0.16 = 0.42 + 0.8 + 0.64 = 1.86.
  const auto mesh = tet_block(5, {0, 0, 0}, {1, 1, 1});
  TransferFunction tf;
  tf.colors = {{0, 1, 1, 1}};
  tf.opacities = {{0.0, 0.0}, {0.5, 2.0}, {1.0, 6.0}};
  GapDepth gap(mesh);
  gap.set_field(field(*mesh, [](const Vec3d& x) { return x.x; }), tf);
  // The scalars are float32 (node values k / 5 rounded to 2^-24 relative): 1e-6 covers that.
  EXPECT_NEAR(gap.depth({0.2, 0.31, 0.77}, {1, 0, 0}, 0.7), 1.86, 1e-6);
}

TEST(GapDepth, HolesAddNothing) {
  // Middle third of x and y removed along z: a segment along x through y = 0.5 crosses 1/3 of
  // medium, the hole, and 1/3 of medium.
  const auto mesh = std::make_shared<const TetMesh>(prepare_tet_mesh(fixtures::tet_block_with_hole(6).view()));
  GapDepth gap(mesh);
  gap.set_field(field(*mesh, [](const Vec3d&) { return 0.0; }), constant_tf(2.0));
  EXPECT_NEAR(gap.depth({0, 0.5, 0.5}, {1, 0, 0}, 1.0), 2.0 * 2.0 / 3.0, 1e-12);
  EXPECT_EQ(gap.depth({0.4, 0.5, 0.5}, {1, 0, 0}, 0.2), 0.0);  // inside the hole
}

TEST(GapDepth, BadInputIsAClearError) {
  EXPECT_THROW(GapDepth(nullptr), Error);
  const auto mesh = tet_block(2, {0, 0, 0}, {1, 1, 1});
  GapDepth gap(mesh);
  EXPECT_THROW(gap.set_field(std::vector<float>(3, 0.0f), constant_tf(1.0)), Error);
  TransferFunction bad;
  EXPECT_THROW(gap.set_field(field(*mesh, [](const Vec3d&) { return 0.0; }), bad), Error);
  // NaN scalars carry no extinction.
  std::vector<float> nan(mesh->points.size(), std::numeric_limits<float>::quiet_NaN());
  gap.set_field(nan, constant_tf(1.0));
  EXPECT_EQ(gap.depth({0.5, 0.5, 0.5}, {1, 0, 0}, 0.3), 0.0);
}

TEST(GapDepth, ShadowsIncludeWhatLiesWithinTheGap) {
  // A sheet of extinction 500, one cell (0.0625) thick, just above the point and inside the cone's
  // gap (3 sigma0 = 0.1875 at 33 nodes on [-1, 1]): the light through it is exp(-31). The cone alone
  // starts past the sheet and sees nothing; with the gap integrated it is dark.
  const auto mesh = tet_block(32, {-1, -1, -1}, {1, 1, 1});
  TransferFunction tf;
  tf.colors = {{0, 1, 1, 1}};
  tf.opacities = {{0.0, 0.0}, {0.999, 0.0}, {1.0, 500.0}};
  const auto s = field(*mesh, [](const Vec3d& x) { return x.z >= 0.0 && x.z <= 0.0625 ? 1.0 : 0.0; });
  const ExtinctionPyramid pyramid(resample_extinction(*mesh, s, tf, 33));
  const ConeTracer cone(pyramid, ConeOptions::shadow(2.0, 1));
  ASSERT_GT(cone.gap(), 0.07);
  GapDepth gap(mesh);
  gap.set_field(s, tf);
  const ShadowLight sun{ShadowLight::Kind::directional, {0, 0, -1}};
  const Vec3d x{0.1, 0.1, -0.001};
  const double exact = std::exp(-gap.depth(x, {0, 0, 1}, 2.0));
  const double without = shadow_transmittance(cone, sun, x), with = shadow_transmittance(cone, sun, x, gap);
  std::printf("sheet within the gap: exact %.3g, cone alone %.4f, with the gap %.3g\n", exact, without, with);
  EXPECT_LT(exact, 1e-10);
  EXPECT_GT(without, 0.99);
  EXPECT_LT(with, 1e-10);
  // Point and spot lights closer than the gap: the segment stops at the light.
  const ShadowLight lamp{ShadowLight::Kind::point, {0.1, 0.1, 0.03}};
  EXPECT_NEAR(shadow_transmittance(cone, lamp, x, gap), std::exp(-gap.depth(x, {0, 0, 1}, 0.031)), 1e-12);
  EXPECT_NEAR(std::log(shadow_transmittance(cone, lamp, x, gap)), -500.0 * 0.03, 0.6);
}

}  // namespace
}  // namespace penumbra::occlusion_test
