// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/occlusion/pyramid_test.cpp -- resampling and the Gaussian extinction pyramid
#include <gtest/gtest.h>

#include <cmath>

#include "occlusion_test_util.h"
#include "penumbra/core/error.h"

namespace penumbra::occlusion_test {
namespace {

// Sum of tau times cell volume over a level: the total extinction "mass".
double mass(const PyramidLevel& l) {
  double s = 0;
  for (float v : l.tau) s += v;
  return s * l.spacing.x * l.spacing.y * l.spacing.z;
}

TEST(ExtinctionPyramid, SigmaDoublesPerLevel) {
  // A single spike spreads into a Gaussian whose second moment along x is sigma_l^2.
  const int n = 65;
  ExtinctionGrid g = grid(n, -1, 1, [](const Vec3d&) { return 0.0; });
  g.tau[g.index(32, 32, 32)] = 1.0f;
  const ExtinctionPyramid p(g, {PyramidQuantity::extinction});
  ASSERT_GE(p.levels(), 4);
  EXPECT_NEAR(p.sigma0(), 2.0 / 64, 1e-12);  // default: mean spacing (sec. 4.2)
  for (int l = 0; l < 4; ++l) {
    const PyramidLevel& lev = p.level(l);
    EXPECT_DOUBLE_EQ(lev.sigma, p.sigma0() * std::pow(2.0, l));
    double m0 = 0, m2 = 0;
    for (int k = 0; k < lev.dims[2]; ++k)
      for (int j = 0; j < lev.dims[1]; ++j)
        for (int i = 0; i < lev.dims[0]; ++i) {
          const double v = lev.tau[static_cast<std::size_t>(i + lev.dims[0] * (j + lev.dims[1] * k))];
          const double x = lev.lo.x + i * lev.spacing.x;
          m0 += v;
          m2 += v * x * x;
        }
    // Sampling a Gaussian of sigma = spacing on its lattice gives the exact variance to 1e-6.
    EXPECT_NEAR(std::sqrt(m2 / m0), lev.sigma, 0.01 * lev.sigma) << "level " << l;
  }
}

TEST(ExtinctionPyramid, ZeroPaddingKeepsMassAtTheBoundary) {
  // tau = 1 in the whole grid: clamp-to-edge would invent extinction beyond the bounds; zero
  // padding spreads exactly the medium's mass, tau times the volume of the bounds (less the < 0.3%
  // Gaussian tail past 3 sigma). At full weight the nodes on the bounds would add half a cell on
  // every face: 33^3 / 32^3 = 1.097.
  const ExtinctionGrid g = grid(33, 0, 1, [](const Vec3d&) { return 1.0; });
  const ExtinctionPyramid p(g, {PyramidQuantity::extinction});
  const double want = 1.0;
  for (int l = 0; l < p.levels(); ++l) EXPECT_NEAR(mass(p.level(l)), want, 0.01 * want) << "level " << l;
  // Beyond 4 sigma outside the bounds nothing is left; at the centre the value is 1.
  EXPECT_LT(p.level(0).sample({-4 * p.sigma0(), 0.5, 0.5}), 1e-3);
  EXPECT_NEAR(p.level(0).sample({0.5, 0.5, 0.5}), 1.0, 1e-5);
  EXPECT_GT(p.build_ms(), 0.0);
  // The unfiltered grid ends at its outermost nodes (the bounds): a ray leaving through a face
  // reads exactly the medium inside.
  const double h = 1.0 / 32;
  EXPECT_EQ(p.fine().sample({1.0, 0.5, 0.5}), 1.0);
  EXPECT_EQ(p.fine().sample({1.0 + 0.25 * h, 0.5, 0.5}), 0.0);
  EXPECT_EQ(p.fine().sample({0.5, -0.25 * h, 0.5}), 0.0);
  double depth = 0;
  for (double x = 0.5 + h / 16; x < 1.5; x += h / 8) depth += p.fine().sample({x, 0.5, 0.5}) * h / 8;
  EXPECT_NEAR(depth, 0.5, 1e-9);
}

TEST(ExtinctionPyramid, CheckerboardAveragesExtinction) {
  // Nodes alternate 0 and 2: the Gaussian of sigma = spacing keeps exp(-pi^2/2) per axis of the
  // alternation, so every level is the mean, 1, to 1e-5 away from the bounds.
  const ExtinctionGrid g = grid(33, 0, 1, [](const Vec3d& x) {
    const int s = static_cast<int>(std::lround(x.x * 32) + std::lround(x.y * 32) + std::lround(x.z * 32));
    return (s % 2) ? 2.0 : 0.0;
  });
  const ExtinctionPyramid p(g, {PyramidQuantity::extinction});
  for (int l = 0; l < 3; ++l) EXPECT_NEAR(p.level(l).sample({0.5, 0.5, 0.5}), 1.0, 1e-3) << "level " << l;
  // Blocks of 4x4x4 nodes: level 0 still shows them, level 2 (sigma = 4 spacings) averages them.
  const ExtinctionGrid b = grid(65, 0, 1, [](const Vec3d& x) {
    const int s = static_cast<int>(std::floor(x.x * 16 + 1e-9) + std::floor(x.y * 16 + 1e-9) + std::floor(x.z * 16 + 1e-9));
    return (s % 2) ? 2.0 : 0.0;
  });
  const ExtinctionPyramid pb(b, {PyramidQuantity::extinction});
  double worst0 = 0, worst2 = 0;
  for (double t = 0.3; t < 0.7; t += 0.01) {
    // y and z at block centres, so the line crosses blocks of both values.
    worst0 = std::max(worst0, std::fabs(pb.level(0).sample({t, 0.53125, 0.53125}) - 1.0));
    worst2 = std::max(worst2, std::fabs(pb.level(2).sample({t, 0.53125, 0.53125}) - 1.0));
  }
  EXPECT_GT(worst0, 0.5);
  EXPECT_LT(worst2, 0.02);
}

TEST(ExtinctionPyramid, OpacityModeIsExactInUniformMediaAndBoundsOpaqueCells) {
  const ExtinctionGrid g = grid(33, 0, 1, [](const Vec3d&) { return 3.0; });
  const ExtinctionPyramid p(g);  // opacity is the default
  for (int l = 0; l < 3; ++l) EXPECT_NEAR(p.level(l).sample({0.5, 0.5, 0.5}), 3.0, 1e-3);
  // One opaque node: extinction filtering spreads 1e6 around it; opacity filtering stays bounded
  // by -ln(1e-6) / cell.
  ExtinctionGrid o = grid(33, 0, 1, [](const Vec3d&) { return 0.0; });
  o.tau[o.index(16, 16, 16)] = 1e6f;
  const ExtinctionPyramid pe(o, {PyramidQuantity::extinction}), po(o, {PyramidQuantity::opacity});
  const Vec3d beside{0.5 + 2.0 / 32, 0.5, 0.5};
  EXPECT_GT(pe.level(0).sample(beside), 1e3);  // 1e6 * 0.054 * 0.399^2
  EXPECT_LT(po.level(0).sample(beside), 20.0);
}

TEST(ExtinctionPyramid, StepOpacityKeepsTheSectionMeanTransmittanceOfAStep) {
  // Sheets across x alternate tau1 and tau2 node by node: any section holds both halves, so a step
  // of D_l = kConeStepSigmas sigma_l lets through 0.5 (exp(-tau1 D) + exp(-tau2 D)) -- the mean
  // of the rays -- and the level's tau must give exactly that over D (the alternation survives a
  // Gaussian of sigma >= 2 spacings as exp(-2 pi^2) ~ 3e-9, hence levels >= 1; float32 rounding
  // bounds the tolerance). Extinction filtering gives the mean tau instead: darker.
  const double tau1 = 0.5, tau2 = 60.0;
  const ExtinctionGrid g = grid(65, 0, 1, [&](const Vec3d& x) { return std::lround(x.x * 64) % 2 ? tau2 : tau1; });
  const ExtinctionPyramid p(g, {PyramidQuantity::step_opacity});
  const ExtinctionPyramid pe(g, {PyramidQuantity::extinction});
  for (int l = 1; l < 4; ++l) {
    const double d = kConeStepSigmas * p.level(l).sigma;
    const double want = -std::log(0.5 * (std::exp(-tau1 * d) + std::exp(-tau2 * d))) / d;
    EXPECT_NEAR(p.level(l).sample({0.5, 0.5, 0.5}), want, 1e-4 * want) << "level " << l;
    EXPECT_NEAR(pe.level(l).sample({0.5, 0.5, 0.5}), 0.5 * (tau1 + tau2), 1e-4 * tau2) << "level " << l;
    EXPECT_LT(want, 0.5 * 0.5 * (tau1 + tau2)) << "level " << l;  // the test can tell the two apart
  }
}

TEST(ExtinctionPyramid, RejectsBadInput) {
  ExtinctionGrid g = grid(8, 0, 1, [](const Vec3d&) { return 1.0; });
  EXPECT_THROW(ExtinctionPyramid(g, {PyramidQuantity::extinction, -1.0}), Error);
  EXPECT_THROW(ExtinctionPyramid(g, {PyramidQuantity::extinction, 0.0, 0}), Error);
  g.tau.pop_back();
  EXPECT_THROW(ExtinctionPyramid{g}, Error);
}

TEST(ResampleExtinction, HolesAndOutsideAreEmpty) {
  const auto mesh = std::make_shared<const TetMesh>(prepare_tet_mesh(fixtures::tet_block_with_hole(6).view()));
  const auto s = field(*mesh, [](const Vec3d&) { return 0.0; });
  const ExtinctionGrid g = resample_extinction(*mesh, s, constant_tf(2.5), 25);
  EXPECT_EQ(g.dims[0], 25);
  int in = 0, out = 0;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        const Vec3d x = g.position(i, j, k);
        const bool hole = x.x > 1.0 / 3 + 1e-6 && x.x < 2.0 / 3 - 1e-6 && x.y > 1.0 / 3 + 1e-6 && x.y < 2.0 / 3 - 1e-6;
        const float v = g.tau[g.index(i, j, k)];
        if (hole) {
          EXPECT_EQ(v, 0.0f);
          ++out;
        } else if (!(std::fabs(x.x - 1.0 / 3) < 0.05 || std::fabs(x.x - 2.0 / 3) < 0.05 || std::fabs(x.y - 1.0 / 3) < 0.05 ||
                     std::fabs(x.y - 2.0 / 3) < 0.05)) {
          EXPECT_FLOAT_EQ(v, 2.5f);
          ++in;
        }
      }
  EXPECT_GT(in, 1000);
  EXPECT_GT(out, 100);
  // A transfer-function change re-evaluates the located nodes only.
  ExtinctionResampler r(mesh, 25);
  const ExtinctionGrid g2 = r.resample(s, constant_tf(5.0));
  ASSERT_EQ(g2.tau.size(), g.tau.size());
  for (std::size_t i = 0; i < g.tau.size(); ++i) EXPECT_FLOAT_EQ(g2.tau[i], 2.0f * g.tau[i]);
  EXPECT_THROW(resample_extinction(*mesh, s, constant_tf(1), 1), Error);
  EXPECT_THROW(resample_extinction(*mesh, {1.0f}, constant_tf(1), 8), Error);
}

}  // namespace
}  // namespace penumbra::occlusion_test
