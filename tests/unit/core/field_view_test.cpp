// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/core/field_view_test.cpp
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/core/field_view.h"

using namespace penumbra;

TEST(FieldView, PointFieldCopiesValues) {
  const auto m = fixtures::block(fixtures::BlockCells::tets, 2, 2, 2, {0, 0, 0}, {1, 1, 1});
  const auto v = fixtures::sample(m, [](double x, double y, double z) { return x + 2 * y + 3 * z; });
  const auto s = point_values(m.view(), fixtures::point_field("f", v));
  ASSERT_EQ(s.size(), v.size());
  for (std::size_t i = 0; i < v.size(); ++i) EXPECT_EQ(s[i], v[i]);
}

TEST(FieldView, CellFieldIsAveragedToPoints) {
  const auto m = fixtures::block(fixtures::BlockCells::hexes, 2, 1, 1, {0, 0, 0}, {2, 1, 1});
  const std::vector<double> cell = {1.0, 3.0};
  FieldView f = fixtures::point_field("c", cell);
  f.association = Association::cell;
  const auto s = point_values(m.view(), f);
  EXPECT_EQ(s[0], 1.0);  // only in cell 0
  EXPECT_EQ(s[1], 2.0);  // shared by both cells
  EXPECT_EQ(s[2], 3.0);  // only in cell 1
}

TEST(FieldView, SizeMismatchNamesBothCounts) {
  const auto m = fixtures::block(fixtures::BlockCells::tets, 1, 1, 1, {0, 0, 0}, {1, 1, 1});
  const std::vector<double> v(5, 0.0);
  try {
    point_values(m.view(), fixtures::point_field("p", v));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "field 'p' has 5 values but mesh has 8 points");
  }
}

TEST(FieldView, NonFiniteValuesBecomeNaNAndAreExcludedFromRange) {
  const auto m = fixtures::block(fixtures::BlockCells::tets, 1, 1, 1, {0, 0, 0}, {1, 1, 1});
  std::vector<double> v(8, 2.0);
  v[1] = std::numeric_limits<double>::infinity();
  v[3] = std::numeric_limits<double>::quiet_NaN();
  v[5] = -1.0;
  const auto s = point_values(m.view(), fixtures::point_field("p", v));
  EXPECT_TRUE(std::isnan(s[1]));
  EXPECT_TRUE(std::isnan(s[3]));
  const auto r = finite_range(s);
  EXPECT_EQ(r.finite_count, 6u);
  EXPECT_DOUBLE_EQ(r.lo, -1.0);
  EXPECT_DOUBLE_EQ(r.hi, 2.0);
}

TEST(FieldView, VectorMagnitudeAndComponent) {
  const auto m = fixtures::block(fixtures::BlockCells::tets, 1, 1, 1, {0, 0, 0}, {1, 1, 1});
  std::vector<double> v(8 * 3, 0.0);
  for (int i = 0; i < 8; ++i) { v[3 * i] = 3; v[3 * i + 1] = 4; }
  FieldView f{"vel", Association::point, ScalarType::float64, 3,
              {reinterpret_cast<const std::byte*>(v.data()), 8, 3 * sizeof(double)}};
  EXPECT_EQ(point_values(m.view(), f)[0], 5.0);
  EXPECT_EQ(point_values(m.view(), f, ComponentMode::component, 1)[0], 4.0);
  EXPECT_THROW(point_values(m.view(), f, ComponentMode::component, 3), Error);
}

TEST(FieldView, MagnitudeOfTinyAndHugeVectors) {
  const auto m = fixtures::block(fixtures::BlockCells::tets, 1, 1, 1, {0, 0, 0}, {1, 1, 1});
  for (double scale : {1e-300, 1e-200, 1.0, 1e200, 1e300}) {
    std::vector<double> v(8 * 3, 0.0);
    for (int i = 0; i < 8; ++i) { v[3 * i] = 3 * scale; v[3 * i + 1] = -4 * scale; }
    v[3 * 7 + 2] = std::numeric_limits<double>::infinity();
    FieldView f{"vel", Association::point, ScalarType::float64, 3,
                {reinterpret_cast<const std::byte*>(v.data()), 8, 3 * sizeof(double)}};
    const auto s = point_values(m.view(), f);
    EXPECT_DOUBLE_EQ(s[0], 5 * scale) << scale;  // the squares alone would overflow or vanish
    EXPECT_TRUE(std::isnan(s[7])) << scale;      // an infinite component: no data
  }
}

TEST(FieldView, NormalizedValuesKeepTheVariationOfAnyMagnitudeAndOffset) {
  for (double magnitude : {1e-300, 1e-20, 1.0, 1e20, 1e300})
    for (double offset : {0.0, 1e6, 1e9}) {
      // Values c + w t, t in [0, 1], of size `magnitude`: the range is w, the offset c = offset * w.
      const double w = magnitude / (1 + offset), c = offset * w;
      std::vector<double> v;
      for (int i = 0; i <= 10; ++i) v.push_back(c + w * (i / 10.0));
      const ValueRange r = finite_range(v);
      const auto u = normalize_values(v, r.lo, r.hi);
      for (int i = 0; i <= 10; ++i)  // the double values hold c + w t to 1e-16 c = 1e-7 w at 1e9
        EXPECT_NEAR(u[static_cast<std::size_t>(i)], i / 10.0, 1e-6) << magnitude << " " << offset << " " << i;
    }
  // The full double range, where hi - lo itself would overflow.
  const double big = std::numeric_limits<double>::max();
  EXPECT_DOUBLE_EQ(normalize_value(0.0, -big, big), 0.5);
  EXPECT_DOUBLE_EQ(normalize_value(big, -big, big), 1.0);
  // Far outside the range: clamped, still finite in float.
  EXPECT_EQ(normalize_value(1e300, 0.0, 1.0), kNormalizedLimit);
  EXPECT_TRUE(std::isnan(normalize_value(std::nan(""), 0.0, 1.0)));
}
