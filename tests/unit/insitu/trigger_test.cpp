// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/trigger_test.cpp -- which steps render
#include <gtest/gtest.h>

#include "trigger.h"

namespace penumbra::insitu {
namespace {

std::vector<std::int64_t> fired_cycles(TriggerConfig c, int steps, double dt) {
  Trigger t(c);
  std::vector<std::int64_t> out;
  for (int i = 0; i < steps; ++i)
    if (t.fires(i * dt, i)) out.push_back(i);
  return out;
}

TEST(Trigger, EveryCyclesUsesTheCycleNumber) {
  EXPECT_EQ(fired_cycles({3, 0}, 10, 0.1), (std::vector<std::int64_t>{0, 3, 6, 9}));
  EXPECT_EQ(fired_cycles({1, 0}, 4, 0.1), (std::vector<std::int64_t>{0, 1, 2, 3}));
  // Restarting mid-run renders the same cycles (no hidden state), negative cycles too.
  Trigger t({4, 0});
  EXPECT_FALSE(t.fires(0, 7));
  EXPECT_TRUE(t.fires(0, 8));
  EXPECT_TRUE(t.fires(0, -4));
}

TEST(Trigger, EveryTimeRendersFirstStepAtOrAfterEachMultiple) {
  // dt = 0.1, T = 0.3: multiples 0, 0.3, 0.6, 0.9 fall on cycles 0, 3, 6, 9.
  EXPECT_EQ(fired_cycles({0, 0.3}, 10, 0.1), (std::vector<std::int64_t>{0, 3, 6, 9}));
  // dt = 0.25, T = 0.6: first steps at or after 0, 0.6, 1.2, 1.8 are t = 0, 0.75, 1.25, 2.0.
  EXPECT_EQ(fired_cycles({0, 0.6}, 9, 0.25), (std::vector<std::int64_t>{0, 3, 5, 8}));
  // Steps larger than T render every step, never twice for one step.
  EXPECT_EQ(fired_cycles({0, 0.1}, 4, 1.0), (std::vector<std::int64_t>{0, 1, 2, 3}));
}

TEST(Trigger, TimeToleratesRoundingBelowAMultiple) {
  // 0.3 / 0.1 = 2.9999999999999996 in doubles: the 1e-9 relative tolerance still counts t = 0.3
  // as the start of interval 3.
  Trigger t({0, 0.1});
  EXPECT_TRUE(t.fires(0.2, 0));
  EXPECT_TRUE(t.fires(0.3, 1));
  EXPECT_FALSE(t.fires(0.35, 2));
}

TEST(Trigger, TimeDoesNotFireAgainWithinAnInterval) {
  Trigger t({0, 1.0});
  EXPECT_TRUE(t.fires(5.2, 0));   // first step seen
  EXPECT_FALSE(t.fires(5.9, 1));
  EXPECT_FALSE(t.fires(5.5, 2));  // time going back inside the interval
  EXPECT_TRUE(t.fires(6.0, 3));
}

TEST(Trigger, BothRulesCombineWithOr) {
  // Cycles 0,4,8 by count; times 0, 0.5, 1.0 (cycles 0, 5, 10) by time.
  EXPECT_EQ(fired_cycles({4, 0.5}, 11, 0.1), (std::vector<std::int64_t>{0, 4, 5, 8, 10}));
}

}  // namespace
}  // namespace penumbra::insitu
