// tests/unit/lighting/vertex_order_test.cpp -- the level-1 vertex order (groups along the light)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "lighting/level1_solve.h"
#include "lighting_test_util.h"

namespace penumbra::lighting_test {
namespace {

// The order must be exactly that of sorting (key, id) pairs by position along the light, ties
// included, cut greedily into groups less than half a step wide, each point in the group it is
// listed in: a faster sort must not change which group a point falls in.
void expect_sorted_order(const TetMesh& mesh, const Light& light, double step) {
  const render::lighting::Level1Topology topology(mesh);
  const auto order = render::lighting::order_vertices(mesh, topology, light, step);
  std::vector<std::pair<double, std::int32_t>> want;
  const Vec3d u = light.kind == Light::Kind::directional ? normalize(light.vector) : Vec3d{};
  for (std::size_t p = 0; p < mesh.points.size(); ++p) {
    const double key = light.kind == Light::Kind::directional ? dot(mesh.points[p], u) : length(mesh.points[p] - light.vector);
    want.emplace_back(key, static_cast<std::int32_t>(p));
  }
  std::sort(want.begin(), want.end());
  ASSERT_EQ(order.vertices.size(), want.size());
  std::size_t begin = 0;
  for (std::size_t g = 0; g < order.group_end.size(); ++g) {
    const std::size_t end = order.group_end[g];
    ASSERT_GT(end, begin);
    // The group holds exactly the next points of the sorted list (in any order within it).
    std::vector<std::int32_t> got(order.vertices.begin() + static_cast<std::ptrdiff_t>(begin),
                                  order.vertices.begin() + static_cast<std::ptrdiff_t>(end));
    std::vector<std::int32_t> expected;
    for (std::size_t i = begin; i < end; ++i) expected.push_back(want[i].second);
    std::sort(got.begin(), got.end());
    std::sort(expected.begin(), expected.end());
    ASSERT_EQ(got, expected) << "group " << g;
    EXPECT_LT(want[end - 1].first - want[begin].first, 0.5 * step) << "group " << g;
    if (end < want.size()) EXPECT_GE(want[end].first - want[begin].first, 0.5 * step) << "group " << g;
    for (std::size_t i = begin; i < end; ++i)
      EXPECT_EQ(order.group_of[static_cast<std::size_t>(order.vertices[i])], static_cast<std::int32_t>(g));
    begin = end;
  }
}

TEST(VertexOrder, GroupsFollowASortOfKeyIdPairs) {
  // Centred on the origin: keys of both signs, and -0.0 beside 0.0.
  const auto mesh = tet_block(6, 6, 6, {-1, -1, -1}, {1, 1, 1});
  expect_sorted_order(*mesh, directional({1, 0, 0}), 0.2);        // whole planes of equal keys
  expect_sorted_order(*mesh, directional({-1, 0.3, 0.2}), 0.15);  // few ties
  expect_sorted_order(*mesh, point_light({0.05, 2.0, -0.3}), 0.3);
}

}  // namespace
}  // namespace penumbra::lighting_test
