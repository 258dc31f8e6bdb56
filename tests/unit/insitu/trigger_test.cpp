// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/trigger_test.cpp -- which steps render
#include <gtest/gtest.h>

#include "penumbra/core/error.h"
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

namespace penumbra::insitu {
namespace {

StatsByField stats_of(double max, double mean = 0) { return {{"T", {0, max, mean}}}; }

TEST(TriggerExpression, ReadsComparisonsJoinedByAndOr) {
  const TriggerExpression e("max(T) > 500 or mean(T) >= 10 and min(p) < -1", "trigger.when");
  EXPECT_EQ(e.fields(), (std::vector<std::string>{"T", "p"}));
  StatsByField s{{"T", {0, 400, 20}}, {"p", {-2, 0, 0}}};
  EXPECT_TRUE(e.holds(s, nullptr));  // the `and` group holds
  s["p"].min = 0;
  EXPECT_FALSE(e.holds(s, nullptr));
  s["T"].max = 501;
  EXPECT_TRUE(e.holds(s, nullptr));
  // A field with no statistics makes its comparisons false.
  EXPECT_FALSE(TriggerExpression("max(q) > 0", "w").holds(s, nullptr));
}

TEST(TriggerExpression, ChangeIsRelativeToWhenItLastFired) {
  const TriggerExpression e("change(mean(T)) > 5%", "trigger.when");
  const StatsByField then = stats_of(0, 100);
  EXPECT_TRUE(e.holds(stats_of(0, 100), nullptr));  // before it ever fired: infinite change
  EXPECT_FALSE(e.holds(stats_of(0, 104), &then));
  EXPECT_TRUE(e.holds(stats_of(0, 94), &then));
  // From zero any change is infinite, and no change is none.
  const StatsByField zero = stats_of(0, 0);
  EXPECT_TRUE(e.holds(stats_of(0, 1e-300), &zero));
  EXPECT_FALSE(e.holds(stats_of(0, 0), &zero));
}

TEST(TriggerExpression, BadTextIsRefusedSayingWhereAndWhat) {
  for (const char* bad : {"", "max(T)", "max(T) > ", "max(T) = 3", "maximum(T) > 1", "max() > 1", "max(T > 1",
                          "max(T) > 1 or", "max(T) > 1 xor min(T) < 0", "change(T) > 1", "max(T) > nan", "max(T) > 1e999"}) {
    try {
      TriggerExpression e(bad, "trigger.when");
      ADD_FAILURE() << "'" << bad << "' was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      EXPECT_NE(std::string(e.what()).find("config: trigger.when: "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("at character"), std::string::npos) << e.what();
    }
  }
}

TEST(Trigger, WhenDecidesFromTheStepBeforeAndChangeFromTheLastFiring) {
  TriggerConfig c;
  c.when = TriggerExpression("max(T) > 500 or change(mean(T)) > 10%", "trigger.when");
  Trigger t(c);
  EXPECT_FALSE(t.would_fire(0, 0));  // nothing observed yet
  EXPECT_FALSE(t.fires(0, 0));
  // max, mean per step; the decision at step k reads step k - 1's statistics.
  const double steps[][2] = {{100, 50}, {200, 52}, {600, 54}, {300, 56}, {300, 60}, {300, 64}};
  std::vector<int> fired;
  for (int k = 0; k < 6; ++k) {
    t.observe(stats_of(steps[k][0], steps[k][1]));
    const bool asked = t.would_fire(k + 1, k + 1);
    const bool fire = t.fires(k + 1, k + 1);
    EXPECT_EQ(asked, fire) << k + 1;
    if (fire) fired.push_back(k + 1);
  }
  // Step 1 (reading step 0): the first change is infinite. Step 2: mean 52 is within 10 % of 50.
  // Step 3: max 600. Step 4: mean 56 is within 10 % of 54, the mean it fired with. Step 5: mean 60
  // is 11 % above 54. Step 6: mean 64 is within 10 % of 60.
  EXPECT_EQ(fired, (std::vector<int>{1, 3, 5}));
}

}  // namespace
}  // namespace penumbra::insitu

namespace penumbra::insitu {
namespace {

TEST(Trigger, MaxShareLeavesStepsOutWhileTheShareIsAboveIt) {
  TriggerConfig c;
  c.every_time = 1.0;
  c.max_share = 0.2;
  Trigger t(c);
  EXPECT_TRUE(t.fires(0.0, 0));
  t.observe_share(0.5);
  EXPECT_FALSE(t.would_fire(1.0, 1));
  EXPECT_FALSE(t.fires(1.0, 1));  // left out, and not recorded:
  t.observe_share(0.1);
  EXPECT_TRUE(t.fires(1.5, 2));   // the same interval's next step takes its place
  EXPECT_FALSE(t.fires(1.7, 3));  // and the interval is then used
}

}  // namespace
}  // namespace penumbra::insitu
