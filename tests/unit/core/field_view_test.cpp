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
  const auto s = point_scalars(m.view(), fixtures::point_field("f", v));
  ASSERT_EQ(s.size(), v.size());
  for (std::size_t i = 0; i < v.size(); ++i) EXPECT_FLOAT_EQ(s[i], static_cast<float>(v[i]));
}

TEST(FieldView, CellFieldIsAveragedToPoints) {
  const auto m = fixtures::block(fixtures::BlockCells::hexes, 2, 1, 1, {0, 0, 0}, {2, 1, 1});
  const std::vector<double> cell = {1.0, 3.0};
  FieldView f = fixtures::point_field("c", cell);
  f.association = Association::cell;
  const auto s = point_scalars(m.view(), f);
  EXPECT_FLOAT_EQ(s[0], 1.0f);  // only in cell 0
  EXPECT_FLOAT_EQ(s[1], 2.0f);  // shared by both cells
  EXPECT_FLOAT_EQ(s[2], 3.0f);  // only in cell 1
}

TEST(FieldView, SizeMismatchNamesBothCounts) {
  const auto m = fixtures::block(fixtures::BlockCells::tets, 1, 1, 1, {0, 0, 0}, {1, 1, 1});
  const std::vector<double> v(5, 0.0);
  try {
    point_scalars(m.view(), fixtures::point_field("p", v));
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
  const auto s = point_scalars(m.view(), fixtures::point_field("p", v));
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
  EXPECT_FLOAT_EQ(point_scalars(m.view(), f)[0], 5.0f);
  EXPECT_FLOAT_EQ(point_scalars(m.view(), f, ComponentMode::component, 1)[0], 4.0f);
  EXPECT_THROW(point_scalars(m.view(), f, ComponentMode::component, 3), Error);
}
