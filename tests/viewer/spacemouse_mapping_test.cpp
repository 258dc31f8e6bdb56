// SPDX-License-Identifier: BSD-3-Clause
// tests/viewer/spacemouse_mapping_test.cpp -- the cap's displacement as a view change: dead zone,
// sensitivity, which way each axis turns the view, buttons on press
#include <gtest/gtest.h>

#include <cmath>

#include "penumbra/core/error.h"
#include "spacemouse_mapping.h"

namespace penumbra::viewer {
namespace {

constexpr double kTick = 0.01;  // seconds one report stands for in these tests

MotionState twisted(std::int16_t rz) {
  MotionState s;
  s.rotation = {0, 0, rz};
  return s;
}

TEST(SpaceMouseMapping, DeadZoneCountsAsRest) {
  const MappingSettings settings{1.0, 20};
  for (const std::int16_t small : {0, 1, -1, 19, -19, 20, -20}) {
    MotionState s;
    s.translation = {small, small, small};
    s.rotation = {small, small, small};
    EXPECT_TRUE(map_motion(s, 0, kTick, settings).idle()) << small;
  }
  EXPECT_FALSE(map_motion(twisted(21), 0, kTick, settings).idle());
}

TEST(SpaceMouseMapping, DeflectionGrowsFromTheDeadZonesEdge) {
  EXPECT_EQ(deflection(20, 20), 0.0);
  EXPECT_DOUBLE_EQ(deflection(21, 20), 1.0 / (kFullDeflection - 20));
  EXPECT_DOUBLE_EQ(deflection(kFullDeflection, 20), 1.0);
  EXPECT_DOUBLE_EQ(deflection(-kFullDeflection, 20), -1.0);
  EXPECT_DOUBLE_EQ(deflection(2000, 20), 1.0);
  EXPECT_DOUBLE_EQ(deflection(-32768, 0), -1.0);
  EXPECT_DOUBLE_EQ(deflection(175, 0), 0.5);
}

TEST(SpaceMouseMapping, RatesAtFullDeflection) {
  MotionState s;
  s.translation = {kFullDeflection, 0, kFullDeflection};
  s.rotation = {kFullDeflection, 0, kFullDeflection};
  const ViewEvent e = map_motion(s, 0, kTick, MappingSettings{1.0, 0});
  EXPECT_DOUBLE_EQ(e.d_phi, -kOrbitDegreesPerSecond * kTick);
  EXPECT_DOUBLE_EQ(e.d_theta, kOrbitDegreesPerSecond * kTick);
  EXPECT_DOUBLE_EQ(e.d_time, kTimeStepsPerSecond * kTick);
  EXPECT_DOUBLE_EQ(e.zoom, std::exp2(kZoomDoublingsPerSecond * kTick));
}

TEST(SpaceMouseMapping, SensitivityScalesEveryRate) {
  MotionState s;
  s.translation = {200, 0, -150};
  s.rotation = {-100, 0, 300};
  const ViewEvent one = map_motion(s, 0, kTick, MappingSettings{1.0, 15});
  const ViewEvent three = map_motion(s, 0, kTick, MappingSettings{3.0, 15});
  EXPECT_DOUBLE_EQ(three.d_phi, 3 * one.d_phi);
  EXPECT_DOUBLE_EQ(three.d_theta, 3 * one.d_theta);
  EXPECT_DOUBLE_EQ(three.d_time, 3 * one.d_time);
  EXPECT_NEAR(std::log(three.zoom), 3 * std::log(one.zoom), 1e-12);
}

TEST(SpaceMouseMapping, SignConventions) {
  const MappingSettings settings;
  // Twisting clockwise seen from above (rz > 0, z pointing down) turns phi as dragging right does.
  EXPECT_LT(map_motion(twisted(200), 0, kTick, settings).d_phi, 0);
  EXPECT_GT(map_motion(twisted(-200), 0, kTick, settings).d_phi, 0);
  MotionState tilt;
  tilt.rotation = {200, 0, 0};
  EXPECT_GT(map_motion(tilt, 0, kTick, settings).d_theta, 0);
  MotionState right;
  right.translation = {200, 0, 0};
  EXPECT_GT(map_motion(right, 0, kTick, settings).d_time, 0);
  MotionState pushed;
  pushed.translation = {0, 0, 200};
  EXPECT_GT(map_motion(pushed, 0, kTick, settings).zoom, 1);
  pushed.translation = {0, 0, -200};
  EXPECT_LT(map_motion(pushed, 0, kTick, settings).zoom, 1);
  // y and ry (pulling towards the user, rolling) leave the view as it is.
  MotionState unused;
  unused.translation = {0, 300, 0};
  unused.rotation = {0, 300, 0};
  EXPECT_TRUE(map_motion(unused, 0, kTick, settings).idle());
}

TEST(SpaceMouseMapping, TimeHeldIsClamped) {
  const MappingSettings settings;
  EXPECT_DOUBLE_EQ(map_motion(twisted(300), 0, 10.0, settings).d_phi, map_motion(twisted(300), 0, kMaxReportSeconds, settings).d_phi);
  EXPECT_TRUE(map_motion(twisted(300), 0, 0.0, settings).idle());
  EXPECT_TRUE(map_motion(twisted(300), 0, -1.0, settings).idle());
}

TEST(SpaceMouseMapping, ButtonsActWhenTheyGoDown) {
  const MappingSettings settings;
  MotionState s;
  s.buttons = 1;
  const ViewEvent reset = map_motion(s, 0, kTick, settings);
  EXPECT_TRUE(reset.reset_view);
  EXPECT_FALSE(reset.toggle_play);
  EXPECT_TRUE(map_motion(s, 1, kTick, settings).idle()) << "held, not pressed again";
  s.buttons = 3;
  const ViewEvent both = map_motion(s, 1, kTick, settings);
  EXPECT_FALSE(both.reset_view);
  EXPECT_TRUE(both.toggle_play);
  s.buttons = 0;
  EXPECT_TRUE(map_motion(s, 3, kTick, settings).idle()) << "released";
}

TEST(SpaceMouseMapping, SettingsOutOfRangeAreClearErrors) {
  EXPECT_NO_THROW(check_settings(MappingSettings{}));
  EXPECT_NO_THROW(check_settings(MappingSettings{10.0, 0}));
  for (const MappingSettings bad : {MappingSettings{0.0, 15}, MappingSettings{-1.0, 15}, MappingSettings{11.0, 15},
                                    MappingSettings{NAN, 15}, MappingSettings{1.0, -1}, MappingSettings{1.0, kFullDeflection}}) {
    try {
      check_settings(bad);
      ADD_FAILURE() << bad.sensitivity << " " << bad.dead_zone;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      EXPECT_NE(std::string(e.what()).find("--spacemouse-"), std::string::npos);
    }
  }
}

}  // namespace
}  // namespace penumbra::viewer
