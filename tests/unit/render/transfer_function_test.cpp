// SPDX-License-Identifier: BSD-3-Clause
#include "penumbra/render/transfer_function.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "penumbra/core/error.h"

namespace penumbra::render {
namespace {

TransferFunction two_point() {
  TransferFunction tf;
  tf.colors = {{0.0, 1, 0, 0}, {2.0, 0, 0, 1}};
  tf.opacities = {{1.0, 0.0}, {3.0, 4.0}};
  return tf;
}

TEST(TransferFunction, InterpolatesLinearlyAndClampsEnds) {
  const auto tf = two_point();
  EXPECT_DOUBLE_EQ(tf.color(0.5).x, 0.75);
  EXPECT_DOUBLE_EQ(tf.color(0.5).z, 0.25);
  EXPECT_DOUBLE_EQ(tf.color(-5).x, 1.0);
  EXPECT_DOUBLE_EQ(tf.color(9).z, 1.0);
  EXPECT_DOUBLE_EQ(tf.extinction(2.0), 2.0);
  EXPECT_DOUBLE_EQ(tf.extinction(0.0), 0.0);
  EXPECT_DOUBLE_EQ(tf.extinction(10.0), 4.0);
}

TEST(TransferFunction, NanIsNoData) {
  const auto tf = two_point();
  EXPECT_EQ(tf.extinction(std::numeric_limits<double>::quiet_NaN()), 0.0);
  EXPECT_EQ(tf.color(std::numeric_limits<double>::quiet_NaN()).x, 0.0);
}

TEST(TransferFunction, BreakpointsAreSortedUniqueUnion) {
  auto tf = two_point();
  tf.opacities.push_back({3.0, 1.0});  // a step at 3 repeats x
  EXPECT_EQ(tf.breakpoints(), (std::vector<double>{0.0, 1.0, 2.0, 3.0}));
}

TEST(TransferFunction, StepAtRepeatedPointTakesRightValue) {
  TransferFunction tf;
  tf.colors = {{0, 1, 1, 1}};
  tf.opacities = {{0, 1.0}, {1, 1.0}, {1, 5.0}, {2, 5.0}};
  EXPECT_DOUBLE_EQ(tf.extinction(0.999), 1.0);
  EXPECT_DOUBLE_EQ(tf.extinction(1.001), 5.0);
}

TEST(TransferFunction, ValidateRejectsBadInput) {
  EXPECT_NO_THROW(two_point().validate());
  TransferFunction empty;
  EXPECT_THROW(empty.validate(), Error);
  auto unsorted = two_point();
  unsorted.colors[1].x = -1;
  EXPECT_THROW(unsorted.validate(), Error);
  auto negative = two_point();
  negative.opacities[0].a = -0.1;
  EXPECT_THROW(negative.validate(), Error);
  auto nan = two_point();
  nan.colors[0].g = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(nan.validate(), Error);
  try {
    negative.validate();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    EXPECT_NE(std::string(e.what()).find("opacities[0]"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace penumbra::render
