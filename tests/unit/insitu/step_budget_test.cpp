// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/step_budget_test.cpp -- "budget": the degradation order of a step over its
// budget, its record in pnb_last_step and the database, and images enlarged to the database's size
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "cinema_database.h"
#include "config.h"
#include "context.h"
#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/render/image.h"
#include "step_budget.h"
#include "step_stages.h"
#include "test_util.h"

namespace penumbra::insitu {
namespace {

using testing::TempDir;

// A step of 8 cameras, 1 field, 100x100 images: 10 ms fixed, a 40 ms light in 5 ms pieces,
// 5 ms of ray casting and 1 ms of writing per image.
StepCosts costs() {
  StepCosts c;
  c.fixed_ms = 10;
  c.light_ms = 40;
  c.light_piece_ms = 5;
  c.render_ms_per_pixel = 5.0 / 10000;
  c.image_ms = 1;
  return c;
}

StepPlan plan(double budget_ms, int level0_now = 128) { return plan_step(budget_ms, costs(), 8, 1, 10000, 128, level0_now); }

TEST(StepBudget, AStepThatFitsGivesUpNothing) {
  const StepPlan p = plan(10 + 40 + 8 * 6);
  EXPECT_FALSE(p.degradation.any());
  EXPECT_LT(p.light_ms, 0);
  EXPECT_EQ(p.degradation.text(), "none");
}

TEST(StepBudget, TheLightIsCarriedOverFirstWithWhatTheImagesLeave) {
  const StepPlan p = plan(10 + 20 + 8 * 6);
  EXPECT_DOUBLE_EQ(p.light_ms, 20);
  EXPECT_EQ(p.degradation.level0_resolution, 0);
  EXPECT_EQ(p.degradation.image_scale, 1.0);
  EXPECT_EQ(p.degradation.cameras, 8);
}

TEST(StepBudget, LevelZeroIsCoarsenedUntilAPieceFitsAndComesBackWhenThereIsRoom) {
  // 1 ms for the light: a 5 ms piece needs level 0 at half its resolution (a piece 8 times cheaper).
  const StepPlan p = plan(10 + 1 + 8 * 6);
  EXPECT_EQ(p.degradation.level0_resolution, 64);
  EXPECT_EQ(p.degradation.image_scale, 1.0);
  // Already at 64 (its costs measured there), a budget with room for 8 times the light goes back.
  StepCosts at64 = costs();
  at64.light_ms = 5;
  at64.light_piece_ms = 5.0 / 8;
  EXPECT_EQ(plan_step(10 + 41 + 48, at64, 8, 1, 10000, 128, 64).degradation.level0_resolution, 0);
  EXPECT_EQ(plan_step(10 + 39 + 48, at64, 8, 1, 10000, 128, 64).degradation.level0_resolution, 64);
}

TEST(StepBudget, ALightThatSolvedNoLevelZeroKeepsItsResolution) {
  // The last step's light converged without a level-0 solve (piece 0): coarsening level 0 would
  // only throw the volume away. The images, over the budget alone, shrink instead.
  StepCosts c = costs();
  c.light_ms = 1;
  c.light_piece_ms = 0;
  const StepPlan p = plan_step(10 + 8 + 20, c, 8, 1, 10000, 128, 128);
  EXPECT_EQ(p.degradation.level0_resolution, 0);
  EXPECT_LT(p.degradation.image_scale, 1.0);
  EXPECT_EQ(p.light_piece_ms, 0);
}

TEST(StepBudget, ImagesShrinkBeforeCamerasAreLeftOut) {
  // Level 0 at its floor of 16 (a piece of 5/512 ms); 8 x 1 ms of writing; half of the
  // ray casting's 40 ms left: a scale of sqrt(1/2), rounded down to 11/16.
  const double least_light = 5.0 / 512;
  StepPlan p = plan(10 + least_light + 8 + 20);
  EXPECT_EQ(p.degradation.level0_resolution, 16);
  EXPECT_DOUBLE_EQ(p.degradation.image_scale, 11.0 / 16);
  EXPECT_EQ(p.degradation.cameras, 8);
  // No room for 8 images even at a quarter of their size: cameras left out, each at a quarter.
  p = plan(10 + least_light + 3 * (1 + 5.0 / 16));
  EXPECT_DOUBLE_EQ(p.degradation.image_scale, 0.25);
  EXPECT_EQ(p.degradation.cameras, 3);
  EXPECT_EQ(p.degradation.text(), "level0:16+image:0.25+cameras:3/8");
  // Never none.
  EXPECT_EQ(plan(0.001).degradation.cameras, 1);
}

TEST(StepBudget, ALowerBudgetGivesUpEverythingAHigherOneDidInTheDocumentedOrder) {
  // Each degradation, once taken as the budget falls, stays taken; none is taken before the
  // ones before it in the order.
  int rank_before = 0;
  for (double budget = 120; budget > 0.01; budget *= 0.93) {
    const StepPlan p = plan(budget);
    const Degradation& d = p.degradation;
    const int rank = d.cameras_reduced() ? 4 : d.image_scale < 1 ? 3 : d.level0_resolution > 0 ? 2 : p.light_ms >= 0 ? 1 : 0;
    EXPECT_GE(rank, rank_before) << "budget " << budget;
    if (d.image_scale < 1) EXPECT_EQ(d.level0_resolution, 16) << "budget " << budget;
    if (d.cameras_reduced()) EXPECT_EQ(d.image_scale, 0.25) << "budget " << budget;
    rank_before = rank;
  }
  EXPECT_EQ(rank_before, 4);
}

TEST(StepBudget, WithoutALightVolumeOnlyImagesAndCamerasGo) {
  StepCosts c = costs();
  c.light_ms = c.light_piece_ms = 0;
  const StepPlan p = plan_step(10 + 8 + 10, c, 8, 1, 10000, 0, 0);
  EXPECT_LT(p.light_ms, 0);
  EXPECT_EQ(p.degradation.level0_resolution, 0);
  EXPECT_DOUBLE_EQ(p.degradation.image_scale, 0.5);
}

TEST(StepBudget, EnlargedImagesKeepFlatAreasAndInterpolateBetweenPixelCentres) {
  ComposedImage small;
  small.width = 2;
  small.height = 1;
  small.rgb = {0, 100, 200, 40, 100, 0};
  const ComposedImage big = enlarged(small, 4, 2);
  ASSERT_EQ(big.rgb.size(), 4u * 2 * 3);
  for (int y = 0; y < 2; ++y) {
    const unsigned char* row = &big.rgb[static_cast<std::size_t>(y) * 4 * 3];
    EXPECT_EQ(row[0], 0);     // left of the first centre: the first pixel
    EXPECT_EQ(row[3], 10);    // a quarter of the way: 0 + 0.25 * 40
    EXPECT_EQ(row[6], 30);
    EXPECT_EQ(row[9], 40);
    EXPECT_EQ(row[1], 100);   // flat stays flat
    EXPECT_EQ(row[10], 100);
    EXPECT_EQ(row[5], 150);   // 200 - 0.25 * 200
  }
  EXPECT_EQ(enlarged(small, 2, 1).rgb, small.rgb);
}

TEST(StepBudget, BadBudgetsAreRefusedByName) {
  const auto refused = [](const std::string& budget, const std::string& needle) {
    try {
      parse_config(testing::small_config("/tmp/unused", R"([{"name": "T"}])", R"(, "budget": )" + budget));
      ADD_FAILURE() << budget << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  refused("{}", "budget needs ms and/or share");
  refused(R"({"ms": 0})", "budget.ms must be > 0");
  refused(R"({"share": -1})", "budget.share must be > 0");
  refused(R"({"seconds": 1})", "seconds");
  refused("5", "budget");
  const Config c = parse_config(testing::small_config("/tmp/unused", R"([{"name": "T"}])", R"(, "budget": {"ms": 40, "share": 0.5})"));
  ASSERT_TRUE(c.budget.has_value());
  EXPECT_EQ(c.budget->ms, 40);
  EXPECT_EQ(c.budget->share, 0.5);
}

const fixtures::OwnedMesh& mesh() {
  static const fixtures::OwnedMesh m = fixtures::tet_block_with_hole(6);
  return m;
}

std::vector<double> wave(int step) {
  return fixtures::sample(mesh(), [step](double x, double y, double z) { return x + 0.3 * std::sin(0.7 * step + 3 * y) + z; });
}

// Four orbit cameras at 48x40, lit by the light volume, with `budget`.
std::string lit_config(const std::string& dir, const std::string& budget) {
  return R"({"output": {"directory": ")" + dir + R"("}, "image": {"width": 48, "height": 40},
             "cameras": {"phi": [0, 90, 180, 270], "theta": [30]}, "fields": [{"name": "T"}],
             "lighting": {"model": "light-volume", "level0_resolution": 32,
                          "lights": [{"type": "directional", "direction": [1, 0.5, -1]}]})" +
         budget + "}";
}

std::vector<std::vector<std::string>> run_steps(Context& c, int steps) {
  c.publish_mesh(mesh().view());
  for (int k = 0; k < steps; ++k) {
    const auto v = wave(k);
    c.publish_field(fixtures::point_field("T", v), false);
    c.execute(0.1 * k, k);
  }
  c.finalize();
  return CinemaDatabase::parse_csv(testing::read_text(c.config().output_directory + "/data.csv"), "data.csv");
}

TEST(StepBudget, AnImpossibleBudgetDegradesEveryStepAfterTheFirstAndSaysSoInTheDatabase) {
  TempDir tmp;
  Context c(parse_config(lit_config(tmp / "db", R"(, "budget": {"ms": 0.001})")));
  const auto table = run_steps(c, 5);
  ASSERT_EQ(table.at(0), (std::vector<std::string>{"time", "phi", "theta", "field", "lighting", "degraded", "FILE"}));
  // Step 0 measures (4 images); then one camera a step, in turn, at a quarter of the size.
  ASSERT_EQ(table.size(), 1u + 4 + 4);
  std::set<std::string> phis;
  for (std::size_t r = 1; r < table.size(); ++r) {
    const bool first = table[r][0] == "0";
    EXPECT_EQ(table[r][5], first ? "none" : "light+level0:16+image:0.25+cameras:1/4") << "row " << r;
    if (!first) phis.insert(table[r][1]);
    int w = 0, h = 0;
    render::read_png_rgb(tmp / "db" + "/" + table[r].back(), w, h);
    EXPECT_EQ(w, 48);  // enlarged back to the database's size
    EXPECT_EQ(h, 40);
  }
  EXPECT_EQ(phis.size(), 4u) << "every camera is refreshed in turn";
  const StepStats& s = c.last_step();
  EXPECT_DOUBLE_EQ(s.budget_ms, 0.001);
  EXPECT_TRUE(s.degradation.light);
  EXPECT_EQ(s.degradation.level0_resolution, 16);
  EXPECT_EQ(s.degradation.cameras, 1);
  EXPECT_EQ(s.images, 1);
}

TEST(StepBudget, AGenerousBudgetChangesNoImage) {
  TempDir tmp;
  Context plain(parse_config(lit_config(tmp / "plain", "")));
  Context budgeted(parse_config(lit_config(tmp / "budgeted", R"(, "budget": {"ms": 1e9})")));
  const auto a = run_steps(plain, 3), b = run_steps(budgeted, 3);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t r = 1; r < a.size(); ++r) {
    EXPECT_EQ(b[r][5], "none");
    EXPECT_EQ(testing::read_text(tmp / "plain" + "/" + a[r].back()), testing::read_text(tmp / "budgeted" + "/" + b[r].back())) << a[r].back();
  }
}

TEST(StepBudget, AShareIsOfTheSolversOwnTimePerStep) {
  TempDir tmp;
  // 0.001 of a 20 ms solver step: 0.02 ms, less than any step takes.
  Context c(parse_config(lit_config(tmp / "db", R"(, "budget": {"share": 0.001})")));
  c.publish_mesh(mesh().view());
  for (int k = 0; k < 3; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    const auto v = wave(k);
    c.publish_field(fixtures::point_field("T", v), false);
    c.execute(0.1 * k, k);
    if (k == 0) EXPECT_EQ(c.last_step().budget_ms, 0) << "no solver step seen yet";
  }
  EXPECT_GT(c.last_step().budget_ms, 0.015);
  EXPECT_LT(c.last_step().budget_ms, 0.2);
  EXPECT_TRUE(c.last_step().degradation.any());
}

}  // namespace
}  // namespace penumbra::insitu
