// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/lighting/vertex_order_test.cpp -- the level-1 vertex order (groups along the light)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "lighting/level1_solve.h"
#include "lighting_test_util.h"

namespace penumbra::lighting_test {
namespace {

// Every point with tets is listed once; the groups are the non-empty slabs of width step / 2
// from the smallest key, in order along the light, each point in the group it is listed in.
void expect_slab_order(const TetMesh& mesh, const Light& light, double step) {
  const render::lighting::Level1Topology topology(mesh);
  const auto order = render::lighting::order_vertices(mesh, topology, light, step);
  const Vec3d u = light.kind == Light::Kind::directional ? normalize(light.vector) : Vec3d{};
  std::vector<double> key(mesh.points.size());
  double k0 = HUGE_VAL;
  for (std::size_t p = 0; p < mesh.points.size(); ++p) {
    key[p] = light.kind == Light::Kind::directional ? dot(mesh.points[p], u) : length(mesh.points[p] - light.vector);
    k0 = std::min(k0, key[p]);
  }
  auto slab = [&](std::int32_t p) { return std::floor((key[static_cast<std::size_t>(p)] - k0) / (0.5 * step)); };
  std::vector<std::int32_t> listed = order.vertices;
  std::sort(listed.begin(), listed.end());
  ASSERT_EQ(listed.size(), mesh.points.size());
  for (std::size_t i = 0; i < listed.size(); ++i) ASSERT_EQ(listed[i], static_cast<std::int32_t>(i));
  std::size_t begin = 0;
  double previous = -1;
  for (std::size_t g = 0; g < order.group_end.size(); ++g) {
    const std::size_t end = order.group_end[g];
    ASSERT_GT(end, begin);
    const double s = slab(order.vertices[begin]);
    EXPECT_GT(s, previous) << "group " << g;
    for (std::size_t i = begin; i < end; ++i) {
      EXPECT_EQ(slab(order.vertices[i]), s) << "group " << g;
      if (i > begin) EXPECT_LT(order.vertices[i - 1], order.vertices[i]) << "group " << g << ": points keep their order";
      EXPECT_EQ(order.group_of[static_cast<std::size_t>(order.vertices[i])], static_cast<std::int32_t>(g));
    }
    previous = s;
    begin = end;
  }
  EXPECT_EQ(begin, order.vertices.size());
}

TEST(VertexOrder, GroupsAreSlabsAlongTheLight) {
  // Centred on the origin: keys of both signs, and -0.0 beside 0.0.
  const auto mesh = tet_block(6, 6, 6, {-1, -1, -1}, {1, 1, 1});
  expect_slab_order(*mesh, directional({1, 0, 0}), 0.2);        // whole planes of equal keys
  expect_slab_order(*mesh, directional({-1, 0.3, 0.2}), 0.15);  // few ties
  expect_slab_order(*mesh, point_light({0.05, 2.0, -0.3}), 0.3);
  expect_slab_order(*mesh, directional({0.2, 1, 0.1}), 1e-4);   // more slabs than points: sorted
}

TEST(VertexOrder, PointsCountedInBlocksKeepTheSameOrder) {
  // 35 937 points: three blocks of the parallel count.
  const auto mesh = tet_block(32, 32, 32, {-1, -1, -1}, {1, 1, 1});
  expect_slab_order(*mesh, directional({-1, 0.3, 0.2}), 0.15);
  expect_slab_order(*mesh, point_light({0.05, 2.0, -0.3}), 0.05);
  // About 56 000 slabs: fewer than twice the points (still counted), but too many to count per
  // block.
  expect_slab_order(*mesh, directional({-1, 0.3, 0.2}), 1e-4);
}

// An order built into the arrays of an earlier one (a light that moved) equals one built anew.
TEST(VertexOrder, ReusedArraysGiveTheSameOrder) {
  const auto mesh = tet_block(12, 12, 12, {-1, -1, -1}, {1, 1, 1});
  const render::lighting::Level1Topology topology(*mesh);
  const Light before = directional({-1, 0.3, 0.2}), after = point_light({0.05, 2.0, -0.3});
  for (double step : {0.15, 1e-4}) {
    auto reused = render::lighting::order_vertices(*mesh, topology, before, 0.2);
    const std::int32_t* storage = reused.vertices.data();
    reused = render::lighting::order_vertices(*mesh, topology, after, step, std::move(reused));
    const auto fresh = render::lighting::order_vertices(*mesh, topology, after, step);
    EXPECT_EQ(reused.vertices, fresh.vertices);
    EXPECT_EQ(reused.group_end, fresh.group_end);
    EXPECT_EQ(reused.group_of, fresh.group_of);
    EXPECT_EQ(reused.path_length, fresh.path_length);
    EXPECT_EQ(reused.vertices.data(), storage) << "the arrays are reused";
  }
}

}  // namespace
}  // namespace penumbra::lighting_test
