// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/lighting/light_update_test.cpp -- incremental updates (Algorithm 1), budgets, errors
#include <gtest/gtest.h>

#include <cmath>

#include "penumbra/core/error.h"
#include "lighting_test_util.h"

namespace penumbra::lighting_test {
namespace {

std::shared_ptr<const TetMesh> cube() { return tet_block(8, 8, 8, {0, 0, 0}, {1, 1, 1}); }

// The largest difference of light k's rho between two volumes on the same mesh.
double max_rho_difference(const LightVolume& a, const LightVolume& b, std::size_t k) {
  const std::vector<float>& ra = a.light_rho(k);
  const std::vector<float>& rb = b.light_rho(k);
  double worst = 0;
  for (std::size_t p = 0; p < ra.size(); ++p) worst = std::max(worst, std::fabs(static_cast<double>(ra[p]) - rb[p]));
  return worst;
}

// A mesh with a through-hole and two fields that light it differently, for the recorded-walk
// tests.
struct TwoFieldScene {
  std::shared_ptr<const TetMesh> mesh = prepare(fixtures::tet_block_with_hole(8));
  LightVolumeOptions opt = [] {
    LightVolumeOptions o;
    o.level0_resolution = 16;
    return o;
  }();
  std::vector<float> first = field(*mesh, [](const Vec3d& p) { return 0.2 + 0.3 * p.x; });
  std::vector<float> second = field(*mesh, [](const Vec3d& p) { return 0.9 - 0.4 * p.y + 0.1 * std::sin(7 * p.z); });
};

// Only the light that changed is recomputed; a colour-only change recombines without
// recomputing; a transfer-function change recomputes every light.
TEST(LightUpdate, OnlyChangedLightsRecompute) {
  const auto mesh = cube();
  LightVolumeOptions opt;
  opt.level0_resolution = 16;
  LightVolume lv(mesh, opt);
  const auto s = field(*mesh, [](const Vec3d& p) { return p.x; });
  lv.set_field(s, ramp_tf(2.0));
  std::vector<Light> lights{directional({1, 0, 0}), directional({0, 1, 0}), point_light({0.5, 0.5, 2})};
  lv.set_lights(lights);
  EXPECT_EQ(lv.update().lights_recomputed, 3);
  EXPECT_EQ(lv.update().lights_recomputed, 0);  // nothing changed
  lights[1].vector = {0, 1, 0.2};
  lv.set_lights(lights);
  auto r = lv.update();
  EXPECT_EQ(r.lights_recomputed, 1);
  EXPECT_TRUE(r.converged);
  lights[2].color = {0.2, 0.2, 0.2};
  lv.set_lights(lights);
  EXPECT_EQ(lv.update().lights_recomputed, 0);
  lv.set_field(s, ramp_tf(1.0));
  EXPECT_EQ(lv.update().lights_recomputed, 3);
  lights.pop_back();
  lv.set_lights(lights);
  EXPECT_EQ(lv.update().lights_recomputed, 0);
}

// A per-frame budget of one work unit: every frame stays within it, the residual is reported
// while the solve is unfinished, and the light converges over frames to the unlimited result.
TEST(LightUpdate, BudgetSpreadsWorkOverFrames) {
  const auto mesh = cube();
  LightVolumeOptions opt;
  opt.level0_resolution = 16;
  opt.sigma_s = {1, 1, 1};
  opt.scatter_tolerance = 1e-8;  // the two runs start their iterations from different states
  const auto s = field(*mesh, [](const Vec3d& p) { return 0.5 + 0.5 * std::sin(5 * p.y); });
  LightVolume full(mesh, opt), stepped(mesh, opt);
  for (auto* lv : {&full, &stepped}) {
    lv->set_field(s, ramp_tf(2.0));
    lv->set_lights({directional({1, 0.3, 0.1}), point_light({1.5, 0.5, 0.5})});
  }
  ASSERT_TRUE(full.update().converged);
  render::LightBudget budget;
  budget.max_work_units = 1;
  int frames = 0;
  for (; frames < 1000; ++frames) {
    const auto r = stepped.update(budget);
    EXPECT_LE(r.work_units, 1);
    if (r.converged) break;
    EXPECT_GT(r.residual, 0.0);
  }
  EXPECT_LT(frames, 1000);
  for (std::size_t i = 0; i < full.light_rgb().size(); ++i)
    ASSERT_NEAR(stepped.light_rgb()[i], full.light_rgb()[i], 1e-5);
  // A time budget of zero: one piece per frame, scattering sweeps cut into blocks between frames.
  LightVolume sliced(mesh, opt);
  sliced.set_field(s, ramp_tf(2.0));
  sliced.set_lights({directional({1, 0.3, 0.1}), point_light({1.5, 0.5, 0.5})});
  render::LightBudget none;
  none.max_ms = 0;
  int sliced_frames = 0, scatter_frames = 0, sweeps = 0;
  for (; sliced_frames < 10000; ++sliced_frames) {
    const auto r = sliced.update(none);
    if (r.l1_scatter_ms > 0) ++scatter_frames;
    sweeps += r.scatter_iterations;
    if (r.converged) break;
  }
  EXPECT_LT(sliced_frames, 10000);
  EXPECT_GT(sweeps, 0);
  EXPECT_GT(scatter_frames, sweeps);  // more frames than sweeps: the sweeps were cut
  for (std::size_t i = 0; i < full.light_rgb().size(); ++i)
    ASSERT_NEAR(sliced.light_rgb()[i], full.light_rgb()[i], 1e-5);
  // A time budget is honoured too: a zero budget still makes progress (the first piece of work
  // always runs) but starts nothing more.
  stepped.set_lights({directional({0, 0, 1})});
  render::LightBudget zero_time;
  zero_time.max_ms = 0;
  const auto r0 = stepped.update(zero_time);
  EXPECT_EQ(r0.work_units, 1);
  EXPECT_EQ(r0.lights_recomputed, 1);
  EXPECT_FALSE(r0.converged);
}

// Between frames only the points a level-1 piece changed are combined and copied out: after
// every frame of a budgeted solve the published colour is still the sum of the lights' current
// values times their colours, at every point of the caller's order (no scattering, so rgb is
// exactly that sum).
TEST(LightUpdate, PublishedColourIsTheLightsSumEveryFrame) {
  const auto mesh = cube();
  LightVolumeOptions opt;
  opt.level0_resolution = 16;
  opt.sigma_s = {0, 0, 0};
  const auto s = field(*mesh, [](const Vec3d& p) { return 0.5 + 0.5 * std::sin(5 * p.y); });
  LightVolume lv(mesh, opt);
  lv.set_field(s, ramp_tf(2.0));
  const std::vector<Light> lights{directional({1, 0.3, 0.1}, {1.0, 0.5, 0.25}), point_light({1.5, 0.5, 0.5}, {0.2, 0.4, 1.0})};
  lv.set_lights(lights);
  render::LightBudget none;
  none.max_ms = 0;  // one piece per frame: a level-1 pass is cut into many
  int frames = 0, partial_frames = 0;
  auto check = [&] {
    const auto& rgb = lv.light_rgb();
    ASSERT_EQ(rgb.size(), 3 * mesh->points.size());
    for (std::size_t p = 0; p < mesh->points.size(); ++p)
      for (int c = 0; c < 3; ++c) {
        float sum = 0.0f;
        for (std::size_t k = 0; k < lights.size(); ++k)
          if (!lv.light_rho(k).empty())  // empty: no value yet (the first frames)
            sum += static_cast<float>(lv.light_rho(k)[p] * lights[k].color[static_cast<std::size_t>(c)]);
        ASSERT_EQ(rgb[3 * p + static_cast<std::size_t>(c)], sum) << "frame " << frames << ", point " << p;
      }
  };
  for (; frames < 10000; ++frames) {
    const auto r = lv.update(none);
    if (r.l1_prop_ms > 0 && r.l0_prop_ms == 0) ++partial_frames;
    check();
    if (r.converged) break;
  }
  EXPECT_LT(frames, 10000);
  EXPECT_GT(partial_frames, 2);
  // The next time step's field: warm passes change a few vertices per frame.
  lv.set_field(field(*mesh, [](const Vec3d& p) { return 0.5 + 0.45 * std::sin(5 * p.y + 0.3); }), ramp_tf(2.0));
  for (int f = 0; f < 10000; ++f) {
    const auto r = lv.update(none);
    check();
    if (r.converged) break;
  }
}

// A field jump between time steps: warm-starting from the previous light converges in no more
// passes than a cold start on the new field, to the same light.
TEST(LightUpdate, FieldJumpWarmStartNoSlowerThanCold) {
  const auto mesh = tet_block(10, 10, 10, {0, 0, 0}, {1, 1, 1});
  LightVolumeOptions opt;
  opt.level0_resolution = 16;
  const auto before = field(*mesh, [](const Vec3d& p) { return 0.5 + 0.5 * std::sin(6 * p.x); });
  const auto after = field(*mesh, [](const Vec3d& p) { return 0.5 + 0.5 * std::cos(5 * p.y + 2 * p.z); });
  const Light light = directional({1, 0.4, 0.3});
  LightVolume warm(mesh, opt), cold(mesh, opt);
  warm.set_field(before, ramp_tf(3.0));
  warm.set_lights({light});
  ASSERT_TRUE(warm.update().converged);
  warm.set_field(after, ramp_tf(3.0));
  const auto rw = warm.update();
  cold.set_field(after, ramp_tf(3.0));
  cold.set_lights({light});
  const auto rc = cold.update();
  ASSERT_TRUE(rw.converged && rc.converged);
  std::printf("passes after the jump: warm %d, cold %d\n", rw.level1_passes, rc.level1_passes);
  EXPECT_LE(rw.level1_passes, rc.level1_passes);
  for (std::size_t p = 0; p < mesh->points.size(); ++p) ASSERT_NEAR(warm.light_rho(0)[p], cold.light_rho(0)[p], 1e-4);
}

// A new field with the same lights replays each vertex's recorded walk (tets, crossing
// parameters, departure weights) instead of walking again. The replay must give what a fresh
// walk gives: on a mesh with a through-hole (walks that leave the mesh and continue in level 0),
// with a directional and a point light and a strong change of the field, the warm light volume
// matches a new one on the second field to the propagation tolerance. A replay that kept the
// first field's optical depths would be off by far more (checked against the first field).
// The light does not depend on the path that led to it: field A, then B, then A again (warm
// starts, replayed walks) gives the light of a fresh solve on A. The mesh's hole has its walls
// on planes of level-0 nodes, where a walk's exit point lies on a cell face: read at the exit
// itself, its float rounding in a replayed walk picked the other cell, and the level-0 value
// there (across the hole or not) differed by up to 0.2.
TEST(LightUpdate, SameFieldSameLightWhateverCameBefore) {
  const auto mesh = prepare(fixtures::tet_block_with_hole(12));
  LightVolumeOptions opt;
  opt.level0_resolution = 13;  // spacing 1/12: the hole's walls at 4/12 and 8/12 are node planes
  const auto a = field(*mesh, [](const Vec3d& p) { return 0.4 + 0.5 * p.y * p.z; });
  const auto b = field(*mesh, [](const Vec3d& p) { return 0.9 - 0.6 * p.x; });
  for (const Light& light : {directional({1, 0.35, 0.2}), point_light({-0.4, 0.55, 0.6})}) {
    LightVolume warm(mesh, opt), fresh(mesh, opt);
    warm.set_lights({light});
    for (const auto* s : {&a, &b, &a}) {
      warm.set_field(*s, ramp_tf(2.5));
      ASSERT_TRUE(warm.update().converged);
    }
    fresh.set_lights({light});
    fresh.set_field(a, ramp_tf(2.5));
    ASSERT_TRUE(fresh.update().converged);
    EXPECT_LT(max_rho_difference(warm, fresh, 0), 1e-5) << (light.kind == Light::Kind::point ? "point" : "directional");
  }
}

// The first light a volume gets works in memory the volume set aside when it was built
// (prime_first_light); a light added later starts with none. Both give the same light, bit for
// bit, through a new field too (replayed walks), for a directional and a point light.
TEST(LightUpdate, FirstLightsPreparedMemoryGivesTheSameLight) {
  const TwoFieldScene sc;
  for (const Light& light : {directional({1, 0.35, 0.2}), point_light({-0.4, 0.55, 0.6})}) {
    LightVolume first(sc.mesh, sc.opt), later(sc.mesh, sc.opt);
    first.set_lights({light});
    later.set_lights({directional({0, 0, 1})});
    later.set_lights({directional({0, 0, 1}), light});
    for (const auto* s : {&sc.first, &sc.second}) {
      first.set_field(*s, ramp_tf(2.0));
      later.set_field(*s, ramp_tf(2.0));
      ASSERT_TRUE(first.update().converged);
      ASSERT_TRUE(later.update().converged);
      EXPECT_EQ(first.light_rho(0), later.light_rho(1)) << (light.kind == Light::Kind::point ? "point" : "directional");
    }
  }
}

TEST(LightUpdate, WalksRecordedAfterALightMoveReplayCorrectly) {
  // A moved light records its walks again into storage its old walks used; the next field
  // replays them. Any walk left pointing at storage another walk took would read its crossings.
  const TwoFieldScene sc;
  const auto& [mesh, opt, first, second] = sc;
  const std::vector<Light> before{directional({1, 0.3, 0.2}), point_light({0.45, 0.5, 1.6})};
  const std::vector<Light> after{directional({0.2, 1, -0.3}), point_light({-0.6, 0.4, 0.5})};
  LightVolume warm(mesh, opt), fresh(mesh, opt);
  warm.set_lights(before);
  warm.set_field(first, ramp_tf(2.5));
  ASSERT_TRUE(warm.update().converged);
  warm.set_lights(after);
  ASSERT_TRUE(warm.update().converged);
  warm.set_field(second, ramp_tf(2.5));
  ASSERT_TRUE(warm.update().converged);
  fresh.set_lights(after);
  fresh.set_field(second, ramp_tf(2.5));
  ASSERT_TRUE(fresh.update().converged);
  for (std::size_t k = 0; k < after.size(); ++k) EXPECT_LT(max_rho_difference(warm, fresh, k), 2e-4) << "light " << k;
}

TEST(LightUpdate, RecordedWalksMatchFreshWalks) {
  const TwoFieldScene sc;
  const auto& [mesh, opt, first, second] = sc;
  const std::vector<Light> lights{directional({1, 0.3, 0.2}), point_light({0.45, 0.5, 1.6})};
  LightVolume warm(mesh, opt), fresh(mesh, opt);
  warm.set_lights(lights);
  warm.set_field(first, ramp_tf(2.5));
  ASSERT_TRUE(warm.update().converged);
  const std::vector<float> rho_first = warm.light_rho(0);
  warm.set_field(second, ramp_tf(2.5));
  ASSERT_TRUE(warm.update().converged);
  fresh.set_lights(lights);
  fresh.set_field(second, ramp_tf(2.5));
  ASSERT_TRUE(fresh.update().converged);
  double worst = 0, moved = 0;
  for (std::size_t k = 0; k < lights.size(); ++k) worst = std::max(worst, max_rho_difference(warm, fresh, k));
  for (std::size_t p = 0; p < mesh->points.size(); ++p)
    moved = std::max(moved, std::fabs(static_cast<double>(fresh.light_rho(0)[p]) - rho_first[p]));
  EXPECT_LT(worst, 2e-4);
  EXPECT_GT(moved, 0.05);  // the two fields light the mesh differently
  // With no memory for recorded walks, every walk is traced anew: the same light.
  LightVolumeOptions no_record = opt;
  no_record.walk_memory_budget_bytes = 0;
  LightVolume traced(mesh, no_record);
  traced.set_lights(lights);
  traced.set_field(first, ramp_tf(2.5));
  ASSERT_TRUE(traced.update().converged);
  traced.set_field(second, ramp_tf(2.5));
  ASSERT_TRUE(traced.update().converged);
  EXPECT_LT(max_rho_difference(traced, warm, 1), 2e-4);
}

// Level-0 memory budget: a resolution that does not fit is reduced, one that cannot fit at all
// is a clear error; bad options and inputs are errors, never aborts.
TEST(LightUpdate, BudgetAndInputErrors) {
  const auto mesh = cube();
  LightVolumeOptions opt;
  opt.level0_resolution = 200;
  opt.level0_memory_budget_bytes = 1 << 20;  // 1 MiB: about 39^3 nodes at 17 bytes each (one light)
  LightVolume lv(mesh, opt);
  const auto dims = lv.level0_dims();
  EXPECT_LT(dims[0], 200);
  EXPECT_GE(dims[0], 32);
  EXPECT_LE(static_cast<std::size_t>(dims[0]) * dims[1] * dims[2] * 17, opt.level0_memory_budget_bytes);

  opt.level0_memory_budget_bytes = 100;
  EXPECT_THROW(LightVolume(mesh, opt), Error);
  LightVolumeOptions bad;
  bad.sigma_a = -1;
  EXPECT_THROW(LightVolume(mesh, bad), Error);
  EXPECT_THROW(LightVolume(nullptr, LightVolumeOptions{}), Error);
  LightVolume ok(mesh, LightVolumeOptions{});
  EXPECT_THROW(ok.update(), Error);  // no field yet
  EXPECT_THROW(ok.set_field(std::vector<float>(3, 0.0f), ramp_tf(1)), Error);
  EXPECT_THROW(ok.set_lights({directional({0, 0, 0})}), Error);
  EXPECT_THROW(ok.set_lights({point_light({NAN, 0, 0})}), Error);
}

}  // namespace
}  // namespace penumbra::lighting_test
