// SPDX-License-Identifier: BSD-3-Clause
// NaN vertex values (cells with a NaN vertex are empty) and constant fields.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "penumbra/core/error.h"
#include "scenes.h"

namespace penumbra {
namespace {

using fixtures::BlockCells;

TEST(NanField, TetsWithNanVertexAreEmptyButWalked) {
  const auto owned = fixtures::block(BlockCells::tets, 4, 4, 4, {0, 0, 0}, {1, 1, 1});
  const auto mesh = test::prepare(owned);
  render::CpuRayCaster caster(mesh);
  std::vector<float> scalars(mesh->points.size(), 0.0f);
  // The grid vertex at (0.5, 0.5, 0.5): id (k * 5 + j) * 5 + i with i = j = k = 2.
  const std::size_t centre = (2 * 5 + 2) * 5 + 2;
  ASSERT_EQ(mesh->points[centre].x, 0.5);
  scalars[centre] = std::numeric_limits<float>::quiet_NaN();
  const auto tf = test::constant_tf(1.0);
  // Along x through the NaN vertex: every tet around (0.5, 0.5, 0.5) is empty. The ray's
  // segments in the cubes of x in [0.25, 0.75] all touch that vertex, so the depth is 0.5.
  const render::Ray ray{{-1, 0.5, 0.5}, {1, 0, 0}};
  const auto r = caster.trace(scalars, tf, ray);
  EXPECT_NEAR(r.length_inside, 1.0, 1e-12);  // still walked through
  EXPECT_NEAR(r.optical_depth, 0.5, 1e-12);
  const auto ref = render::trace_reference(*mesh, scalars, tf, ray);
  EXPECT_NEAR(ref.optical_depth, r.optical_depth, 1e-12);
  // An off-axis ray matches the reference too.
  const render::Ray slant{{-1, 0.4, 0.55}, normalize(Vec3d{1, 0.1, 0.02})};
  const auto a = caster.trace(scalars, tf, slant), b = render::trace_reference(*mesh, scalars, tf, slant);
  EXPECT_NEAR(a.optical_depth, b.optical_depth, 1e-12);
  EXPECT_LT(a.optical_depth, 1.0 * a.length_inside - 1e-3);  // some of it was empty
}

TEST(NanField, AllNanFieldRendersTransparent) {
  const auto mesh = test::prepare(fixtures::block(BlockCells::tets, 3, 3, 3, {0, 0, 0}, {1, 1, 1}));
  render::CpuRayCaster caster(mesh);
  const std::vector<float> scalars(mesh->points.size(), std::numeric_limits<float>::quiet_NaN());
  const auto cam = render::Camera::orbit(mesh->bounds, 10, 20, 30, 16, 16);
  const auto img = caster.render(scalars, test::constant_tf(3.0), cam);
  for (float v : img.rgba) EXPECT_EQ(v, 0.0f);
}

TEST(ConstantField, ConstantFieldGivesBeerLambertWithTfValueAtConstant) {
  const auto mesh = test::prepare(fixtures::block(BlockCells::tets, 3, 4, 5, {0, 0, 0}, {1, 1, 1}));
  render::CpuRayCaster caster(mesh);
  const std::vector<float> scalars(mesh->points.size(), 0.25f);
  render::TransferFunction tf;
  tf.colors = {{0.0, 1, 0, 0}, {1.0, 0, 0, 1}};
  tf.opacities = {{0.0, 0.0}, {1.0, 4.0}};  // extinction 1 and colour (0.75, 0, 0.25) at s = 0.25
  const render::Ray ray{{-1, 0.3, 0.6}, {1, 0, 0}};
  const auto r = caster.trace(scalars, tf, ray);
  const double t = std::exp(-1.0);
  EXPECT_NEAR(r.optical_depth, 1.0, 1e-12);
  EXPECT_NEAR(r.rgba[0], 0.75 * (1 - t), 1e-12);
  EXPECT_NEAR(r.rgba[1], 0.0, 1e-15);
  EXPECT_NEAR(r.rgba[2], 0.25 * (1 - t), 1e-12);
}

TEST(ConstantField, ZeroOpacityRangeIsSkippedAndInvisible) {
  const auto mesh = test::prepare(fixtures::block(BlockCells::tets, 3, 3, 3, {0, 0, 0}, {1, 1, 1}));
  render::CpuRayCaster caster(mesh);
  const std::vector<float> scalars(mesh->points.size(), -5.0f);
  render::TransferFunction tf;
  tf.colors = {{0.0, 1, 1, 1}};
  tf.opacities = {{0.0, 0.0}, {1.0, 3.0}};  // zero below 0, clamped
  const auto r = caster.trace(scalars, tf, {{-1, 0.5, 0.5}, {1, 0, 0}});
  EXPECT_EQ(r.optical_depth, 0.0);
  EXPECT_NEAR(r.length_inside, 1.0, 1e-12);
}

TEST(RayCasterInputs, MismatchedScalarsAndBadTfThrow) {
  const auto mesh = test::prepare(fixtures::block(BlockCells::tets, 2, 2, 2, {0, 0, 0}, {1, 1, 1}));
  render::CpuRayCaster caster(mesh);
  const auto cam = render::Camera::orbit(mesh->bounds, 0, 0, 30, 8, 8);
  EXPECT_THROW(caster.render(std::vector<float>(3, 0.0f), test::constant_tf(1), cam), Error);
  render::TransferFunction bad;
  bad.colors = {{0, 1, 1, 1}};
  bad.opacities = {{0, -1}};
  EXPECT_THROW(caster.render(std::vector<float>(mesh->points.size(), 0.0f), bad, cam), Error);
  EXPECT_THROW(render::CpuRayCaster(nullptr), Error);
}

}  // namespace
}  // namespace penumbra
