// SPDX-License-Identifier: BSD-3-Clause
#include "ray_frame.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

namespace penumbra::render::detail {
namespace {

// Bit-for-bit equality, so that +0 and -0 (equal as numbers, both "no sign") count as one value.
bool same_magnitude(double x, double y) {
  if (x == 0 && y == 0) return true;
  return std::memcmp(&x, &y, sizeof x) == 0;
}

// Called through a pointer so that each call is compiled on its own, as in a walk step: inlined
// side by side, a compiler may round both orders alike even where it fuses products.
double (*volatile edge_of)(const Projected&, const Projected&) = edge_value;

// The walk's watertightness rests on every tet of an edge seeing the same value for it, up to
// the sign its direction gives (ray_frame.h, rule 1). Coordinates span many magnitudes and
// include near-cancelling pairs, where a fused product would round differently.
TEST(RayFrame, EdgeValueIsExactlyAntisymmetric) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-40, 40);
  int zeros = 0;
  for (int i = 0; i < 200000; ++i) {
    Projected a{std::ldexp(unit(rng), exponent(rng)), std::ldexp(unit(rng), exponent(rng)), 0.0};
    Projected b{std::ldexp(unit(rng), exponent(rng)), std::ldexp(unit(rng), exponent(rng)), 0.0};
    if (i % 3 == 0) b = {a.x * 3.0, a.y * 3.0 * (1.0 + 1e-16 * (i % 7)), 0.0};  // nearly collinear with the ray
    const double ab = edge_of(a, b), ba = edge_of(b, a);
    ASSERT_TRUE(same_magnitude(ab, -ba)) << "a=(" << a.x << ", " << a.y << ") b=(" << b.x << ", " << b.y << ") "
                                         << ab << " vs " << ba;
    zeros += ab == 0;
  }
  EXPECT_GT(zeros, 0);  // the exactly collinear cases were reached
}

// Ties (the ray meets the edge's line) are broken the same way from both ends.
TEST(RayFrame, TieRuleIsAntisymmetric) {
  const Projected a{0.5, 0.25, 0}, b{1.0, 0.5, 0}, c{2.0, 0.5, 0}, d{-1.0, -0.5, 0};
  ASSERT_EQ(edge_value(a, b), 0.0);
  EXPECT_EQ(edge_sign(0.0, a, 3, b, 9), -edge_sign(-0.0, b, 9, a, 3));
  EXPECT_NE(edge_sign(0.0, a, 3, b, 9), 0);
  EXPECT_EQ(edge_positive(edge_value(a, d), a, 4, d, 2), !edge_positive(edge_value(d, a), d, 2, a, 4));
  EXPECT_LT(edge_sign(edge_value(a, c), a, 1, c, 2), 0);  // 0.5 * 0.5 - 0.25 * 2
}

}  // namespace
}  // namespace penumbra::render::detail
