// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/occlusion/cone_tracer_test.cpp -- cone schedule, homogeneous media, domain boundary
#include <gtest/gtest.h>

#include <cmath>

#include "occlusion_test_util.h"
#include "penumbra/core/error.h"

namespace penumbra::occlusion_test {
namespace {

TEST(ConeTracer, ScheduleFollowsTheThesis) {
  const ExtinctionPyramid p(grid(65, -1, 1, [](const Vec3d&) { return 0.0; }));
  const double s0 = p.sigma0();
  ConeOptions o = ConeOptions::occlusion(20.0, 7);
  o.unfiltered_grid = false;  // level 0 for the narrowest sections too (see the next test)
  const ConeTracer t(p, o);
  const auto& s = t.schedule();
  ASSERT_GT(s.size(), 5u);
  EXPECT_DOUBLE_EQ(s.front().distance, 3.0 * s0);  // h0 = 3 sigma0
  EXPECT_DOUBLE_EQ(t.length(), 0.5 * std::sqrt(12.0));
  EXPECT_DOUBLE_EQ(s.back().distance, t.length());
  bool saw3 = false, saw7 = false, saw_blend = false;
  for (std::size_t i = 1; i + 1 < s.size(); ++i) {
    // Continuous level lambda = level + blend; its sigma is sigma0 2^lambda.
    const double lambda_prev = s[i - 1].level + s[i - 1].blend, lambda = s[i].level + s[i].blend;
    EXPECT_GE(s[i].blend, 0.0);
    EXPECT_LT(s[i].blend, 1.0);
    EXPECT_GE(lambda, lambda_prev - 1e-12);
    // Steps of 2.5 sigma_lambda of the previous sample (appendix A, with a continuous level).
    EXPECT_NEAR(s[i].distance - s[i - 1].distance, 2.5 * s0 * std::exp2(lambda_prev), 1e-12);
    EXPECT_GE(s[i].cones, s[i - 1].cones);
    // Levels only climb once all splits are used.
    if (lambda > 0) EXPECT_EQ(s[i].cones, 7);
    saw3 = saw3 || s[i].cones == 3;
    saw7 = saw7 || s[i].cones == 7;
    saw_blend = saw_blend || s[i].blend > 0.1;
    // The filter's sigma is r / 2 (a uniform disc's per-axis standard deviation) once the section
    // outgrows r_c = 2 sigma0, below the top level.
    const double tan_sub = std::tan(20.0 * kPi / 180) * (s[i].cones == 1 ? 1.0 : (s[i].cones == 3 ? 0.4641016 : 1.0 / 3));
    const double r = s[i].distance * tan_sub;
    if (lambda > 0 && s[i].level < p.levels() - 1) EXPECT_NEAR(s0 * std::exp2(lambda), 0.5 * r, 1e-9 * r);
    if (lambda == 0) EXPECT_LE(r, 2.0 * s0 * (1 + 1e-9));
  }
  EXPECT_TRUE(saw_blend);
  EXPECT_TRUE(saw3);
  EXPECT_TRUE(saw7);
}

// LevelSelection::thesis (sec. 3.2.3, appendix A): whole levels only, the finest whose r_c = 2 sigma_l
// holds the section (2 sigma_{l-1} < r <= 2 sigma_l), one fetch per sample, steps of 2.5 sigma_l.
TEST(ConeTracer, ThesisLevelsStepAtTwiceSigma) {
  const ExtinctionPyramid p(grid(65, -1, 1, [](const Vec3d&) { return 0.0; }));
  const double s0 = p.sigma0();
  for (int splits : {1, 3, 7}) {
    ConeOptions o = ConeOptions::occlusion(20.0, splits);  // unfiltered_grid left on: thesis ignores it
    o.level = LevelSelection::thesis;
    const ConeTracer t(p, o);
    const auto& s = t.schedule();
    ASSERT_GT(s.size(), 5u);
    int climbs = 0;
    for (std::size_t i = 0; i < s.size(); ++i) {
      EXPECT_EQ(s[i].blend, 0.0);
      EXPECT_GE(s[i].level, 0) << "sample " << i;  // level 0 near the apex, never the unfiltered grid
      const double tan_sub = std::tan(20.0 * kPi / 180) * (s[i].cones == 1 ? 1.0 : (s[i].cones == 3 ? 0.4641016 : 1.0 / 3));
      const double r = s[i].distance * tan_sub, sigma = s0 * std::exp2(s[i].level);
      if (s[i].level < p.levels() - 1) EXPECT_LE(r, 2.0 * sigma * (1 + 1e-6)) << "sample " << i;
      if (s[i].level > 0) EXPECT_GT(r, sigma * (1 - 1e-6)) << "sample " << i;  // 2 sigma_{l-1}
      if (i == 0) continue;
      EXPECT_GE(s[i].level, s[i - 1].level);
      climbs += s[i].level > s[i - 1].level;
      if (i + 1 < s.size())
        EXPECT_NEAR(s[i].distance - s[i - 1].distance, 2.5 * s0 * std::exp2(s[i - 1].level), 1e-12);
    }
    EXPECT_GE(climbs, 2) << "splits " << splits;
  }
}

// Sections narrower than level 0's filter read the unfiltered grid, blended toward level 0 with
// sigma = max(h / sqrt 6, r / 2) (linear in log2 sigma), in steps of 2.5 times that sigma; from
// r = 2 sigma0 on, the pyramid's levels as before.
TEST(ConeTracer, NarrowSectionsReadTheUnfilteredGrid) {
  const ExtinctionPyramid p(grid(65, -1, 1, [](const Vec3d&) { return 0.0; }));
  const double s0 = p.sigma0(), fine = p.fine().sigma;
  EXPECT_NEAR(fine, s0 / std::sqrt(6.0), 1e-15);
  const ConeTracer t(p, ConeOptions::shadow(2.0, 1));
  const auto& s = t.schedule();
  const double tan_theta = std::tan(2.0 * kPi / 180);
  int below = 0, above = 0;
  for (std::size_t i = 0; i + 1 < s.size(); ++i) {
    const double r = s[i].distance * tan_theta;
    if (r < 2.0 * s0) {
      ++below;
      ASSERT_EQ(s[i].level, kFineLevel) << i;
      const double sigma = std::max(fine, 0.5 * r);
      EXPECT_NEAR(s[i].blend, std::log2(sigma / fine) / std::log2(s0 / fine), 1e-12) << i;
      if (i > 0) EXPECT_NEAR(s[i + 1].distance - s[i].distance, 2.5 * sigma, 1e-12) << i;
    } else {
      ++above;
      EXPECT_GE(s[i].level, 0) << i;
    }
  }
  EXPECT_GT(below, 5);
  EXPECT_GT(above, 5);
  // A thin absorbing sheet across the axis, 0.3 ahead, in the half x >= 0: two node planes at
  // tau = 20, so the grid's trilinear profile integrates to 20 * 2h along z. A narrow cone through
  // it reads that depth from the unfiltered grid; level 0 (opacity filtered over a cell, then
  // blurred) reads less. A cone passing beside the sheet's edge at 1.5 level-0 sigmas sees much
  // less of it than level 0's wider filter pulls in.
  const double h = 2.0 / 64;
  const ExtinctionPyramid sheet(grid(65, -1, 1, [&](const Vec3d& x) { return x.x >= 0 && std::fabs(x.z - 0.3) <= h ? 20.0 : 0.0; }));
  const double exact = std::exp(-20.0 * 2.0 * h);
  ConeOptions narrow = ConeOptions::shadow(0.5, 1);
  narrow.length = 0.8;
  narrow.gap = -1.0;  // 3 sigma0, both tracers: the sheet lies well past it
  const ConeTracer with(sheet, narrow);
  narrow.unfiltered_grid = false;
  const ConeTracer without(sheet, narrow);
  const Vec3d beside{-1.5 * sheet.sigma0(), 0.0, 0.0};
  EXPECT_GT(with.transmittance(beside, {0, 0, 1}), without.transmittance(beside, {0, 0, 1}) + 0.05);
  const Vec3d through{0.3, 0.0, 0.0};
  EXPECT_NEAR(with.transmittance(through, {0, 0, 1}), exact, 0.01);  // the trapezoid over a tent
  EXPECT_GT(std::fabs(without.transmittance(through, {0, 0, 1}) - exact), 0.05);
}

// Infinite (large) homogeneous medium: T = exp(-tau (L - h0)) for every aperture and split count.
// The trapezoid rule on a constant is exact and the pyramid is exact away from the bounds, so the
// tolerance is float rounding (1e-5 relative in depth).
TEST(ConeTracer, HomogeneousMediumIsExactForEveryApertureAndSplit) {
  // The grid reaches 4.5 sigma of the coarsest level used beyond every cone section.
  const double tau = 1.0;
  for (PyramidQuantity q : {PyramidQuantity::extinction, PyramidQuantity::opacity, PyramidQuantity::step_opacity}) {
    const ExtinctionPyramid p(grid(121, -6, 6, [&](const Vec3d&) { return tau; }), {q});
    for (double aperture : {0.5, 2.0, 10.0, 20.0, 30.0})
      for (int splits : {1, 3, 7})
        for (LevelSelection level : {LevelSelection::continuous, LevelSelection::thesis}) {
          ConeOptions o = ConeOptions::occlusion(aperture, splits);
          o.length = 1.5;
          o.level = level;
          const ConeTracer t(p, o);
          const double want = std::exp(-tau * (o.length - t.gap()));
          EXPECT_NEAR(t.transmittance({0.1, -0.2, 0.05}, {1, 2, 3}), want, 1e-5 * want)
              << "aperture " << aperture << " splits " << splits << " thesis levels " << (level == LevelSelection::thesis);
        }
  }
}

TEST(ConeTracer, ThesisSectionWeightIsFourOverPiForNarrowCones) {
  // Eq. 3-15 with r << sigma: (p_r sigma sqrt(2 pi))^2 / (pi r^2) -> 4 / pi (square truncation
  // over a disc), so a uniform medium darkens by that factor: the bias alpha compensates.
  const ExtinctionPyramid p(grid(65, -2, 2, [](const Vec3d&) { return 1.0; }));
  ConeOptions o = ConeOptions::shadow(0.001, 1);
  o.length = 0.5;
  o.weight = SectionWeight::thesis;
  const ConeTracer t(p, o);
  EXPECT_NEAR(t.transmittance({0, 0, 0}, {0, 0, 1}), std::exp(-4.0 / kPi * (o.length - t.gap())), 1e-5);
  o.attenuation = kPi / 4;
  const ConeTracer ta(p, o);
  EXPECT_NEAR(ta.transmittance({0, 0, 0}, {0, 0, 1}), std::exp(-(o.length - ta.gap())), 1e-5);
}

TEST(ConeTracer, ConesLeavingTheDomainDoNotDarken) {
  // tau = 3 in [0, 1]^3 and 0 outside. From 0.25 before the x = 1 face, a cone of length 0.9
  // crosses 0.25 - h0 of medium; clamp-to-edge would charge all of L - h0.
  const ExtinctionPyramid p(grid(49, 0, 1, [](const Vec3d&) { return 3.0; }));
  for (double aperture : {2.0, 10.0})
    for (int splits : {1, 3, 7}) {
      ConeOptions o = ConeOptions::occlusion(aperture, splits);
      o.length = 0.9;
      const ConeTracer t(p, o);
      const double got = t.transmittance({0.75, 0.5, 0.5}, {1, 0, 0});
      const double want = std::exp(-3.0 * (0.25 - t.gap()));
      // The blurred face integrates like the sharp one; what remains is the trapezoid rule on the
      // blurred step with samples 2.5 sigma apart (measured up to 0.04).
      EXPECT_NEAR(got, want, 0.06) << "aperture " << aperture << " splits " << splits;
      EXPECT_GT(got, 3 * std::exp(-3.0 * (o.length - t.gap())));
    }
  // An empty volume never occludes.
  const ExtinctionPyramid empty(grid(17, 0, 1, [](const Vec3d&) { return 0.0; }));
  EXPECT_EQ(ConeTracer(empty, ConeOptions::occlusion(15, 7)).transmittance({0.5, 0.5, 0.5}, {0, 1, 0}), 1.0);
}

TEST(ConeTracer, PointLightConeStopsAtTheLight) {
  // Medium only beyond the light: nothing occludes it.
  const ExtinctionPyramid p(grid(49, 0, 1, [](const Vec3d& x) { return x.z > 0.6 ? 50.0 : 0.0; }));
  const ConeTracer t(p, ConeOptions::shadow(1.0, 1));
  ShadowLight light{ShadowLight::Kind::point, {0.5, 0.5, 0.45}};
  EXPECT_NEAR(shadow_transmittance(t, light, {0.5, 0.5, 0.1}), 1.0, 1e-6);
  // A directional light from +z sees the slab.
  EXPECT_LT(shadow_transmittance(t, {ShadowLight::Kind::directional, {0, 0, -1}}, {0.5, 0.5, 0.1}), 1e-3);
  // A spot pointing away leaves the point dark; pointing at it, lit.
  ShadowLight spot{ShadowLight::Kind::spot, {0.5, 0.5, 0.45}, {0, 0, 1}, 20};
  EXPECT_EQ(shadow_transmittance(t, spot, {0.5, 0.5, 0.1}), 0.0);
  spot.spot_direction = {0, 0, -1};
  EXPECT_NEAR(shadow_transmittance(t, spot, {0.5, 0.5, 0.1}), 1.0, 1e-6);
}

TEST(ConeTracer, RejectsBadOptions) {
  const ExtinctionPyramid p(grid(9, 0, 1, [](const Vec3d&) { return 0.0; }));
  ConeOptions o;
  o.splits = 2;
  EXPECT_THROW(ConeTracer(p, o), Error);
  o = {};
  o.aperture_deg = 0;
  EXPECT_THROW(ConeTracer(p, o), Error);
  o = {};
  o.attenuation = 0;
  EXPECT_THROW(ConeTracer(p, o), Error);
  const ExtinctionPyramid none;
  EXPECT_THROW(ConeTracer(none, ConeOptions{}), Error);
}

TEST(PreIlluminationVolume, InterpolatesNodeValues) {
  Bounds b;
  b.extend({0, 0, 0});
  b.extend({2, 1, 1});
  const PreIlluminationVolume v(b, 9, [](const Vec3d& x) { return 0.1 + 0.2 * x.x - 0.3 * x.y + 0.05 * x.z; });
  EXPECT_EQ(v.dims()[0], 9);
  EXPECT_EQ(v.dims()[1], 5);
  EXPECT_NEAR(v.sample({0.77, 0.31, 0.9}), 0.1 + 0.2 * 0.77 - 0.3 * 0.31 + 0.05 * 0.9, 1e-6);
  EXPECT_THROW(PreIlluminationVolume(b, 1, [](const Vec3d&) { return 0.0; }), Error);
}

}  // namespace
}  // namespace penumbra::occlusion_test

namespace penumbra::occlusion_test {
namespace {

TEST(ObjectSpace, PreIlluminationConvergesToImageSpace) {
  // Occlusion towards a fixed eye, precomputed at two resolutions and sampled off the nodes: the
  // interpolation error against the per-point (image-space) value falls as the volume refines.
  const ExtinctionPyramid p(grid(49, 0, 1, [](const Vec3d& x) { return 6.0 * std::exp(-20 * length(x - Vec3d{0.5, 0.5, 0.7}) * length(x - Vec3d{0.5, 0.5, 0.7})); }));
  const ConeTracer t(p, ConeOptions::occlusion(20, 3));
  const Vec3d eye{0.5, 0.5, 4};
  auto ao = [&](const Vec3d& x) { return directional_occlusion(t, x, eye); };
  const PreIlluminationVolume coarse(p.bounds(), 9, ao), fine(p.bounds(), 33, ao);
  double err_coarse = 0, err_fine = 0;
  for (double x = 0.11; x < 0.9; x += 0.077)
    for (double z = 0.13; z < 0.6; z += 0.061) {
      const Vec3d q{x, 0.47, z};
      err_coarse = std::max(err_coarse, std::fabs(coarse.sample(q) - ao(q)));
      err_fine = std::max(err_fine, std::fabs(fine.sample(q) - ao(q)));
    }
  std::printf("object vs image space: max error %.4f at 9^3, %.4f at 33^3\n", err_coarse, err_fine);
  EXPECT_LT(err_fine, 0.5 * err_coarse);
  EXPECT_LT(err_fine, 0.02);
  EXPECT_GT(coarse.build_ms(), 0.0);
}

TEST(PerPoint, FieldsForTheRenderer) {
  const auto mesh = tet_block(4, {0, 0, 0}, {1, 1, 1});
  const auto v = evaluate_at_points(*mesh, [](const Vec3d& x) { return x.z; });
  ASSERT_EQ(v.size(), mesh->points.size());
  for (std::size_t i = 0; i < v.size(); ++i) EXPECT_FLOAT_EQ(v[i], static_cast<float>(mesh->points[i].z));
  const auto rgb = grey_light_rgb(v, 2.0);
  ASSERT_EQ(rgb.size(), 3 * v.size());
  EXPECT_FLOAT_EQ(rgb[3 * 5 + 1], 2.0f * v[5]);
}

}  // namespace
}  // namespace penumbra::occlusion_test
