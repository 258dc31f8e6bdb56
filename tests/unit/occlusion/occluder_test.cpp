// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/occlusion/occluder_test.cpp -- opaque occluders against analytic cone fractions
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "occlusion_test_util.h"

namespace penumbra::occlusion_test {
namespace {

// Transmittance of a cone from (0, 0, -0.5) along +z through a grid holding the occluder.
double trace(const ExtinctionPyramid& p, double aperture, int splits) {
  ConeOptions o = ConeOptions::occlusion(aperture, splits);
  o.length = 1.3;
  return ConeTracer(p, o).transmittance({0, 0, -0.5}, {0, 0, 1});
}

TEST(ConeOccluders, ThinOpaquePlateIsNotBlurredAwayBySplits) {
  // A plate two cells thick, 0.8 ahead, wider than every cone: exactly no light passes. With one
  // cone the section outgrows r_c early, the plate is read from a coarse level where its opacity
  // is spread over sigma >> thickness, and light leaks through; splits keep finer levels longer.
  const double h = 2.0 / 96;
  const ExtinctionPyramid p(grid(97, -1, 1, [&](const Vec3d& x) {
    return std::fabs(x.z - 0.3) <= h && std::fabs(x.x) < 0.95 && std::fabs(x.y) < 0.95 ? 1e4 : 0.0;
  }));
  for (double beta : {15.0, 25.0}) {
    const double t1 = trace(p, beta, 1), t3 = trace(p, beta, 3), t7 = trace(p, beta, 7);
    std::printf("plate beta %.0f: exact 0  splits1 %.4f  splits3 %.4f  splits7 %.4f\n", beta, t1, t3, t7);
    EXPECT_GT(t1, 0.1) << beta;
    EXPECT_LT(t3, t1) << beta;
    EXPECT_LT(t7, t3) << beta;
  }
}

TEST(ConeOccluders, LateralVarianceBringsAHalfSpaceEdgeCloserToExact) {
  // A medium filling x > 0, the cone's apex on its boundary plane: every ray with a positive x
  // component crosses depth tau (L - h0), every other ray nothing, so the cosine-weighted
  // transmittance is exactly (1 + exp(-tau (L - h0))) / 2. exp(-mean depth) per sub-cone is darker
  // (the sub-cone on the edge averages lit and shadowed rays); the lateral variance, taken from the
  // spread between the sub-cones, must bring every split count and aperture closer, and never
  // past the exact value (the linear model understates a step's variance).
  const double tau = 2.0;
  const ExtinctionPyramid p(grid(97, -1, 1, [&](const Vec3d& x) { return x.x > 0 ? tau : x.x == 0 ? tau / 2 : 0.0; }));
  for (int splits : {3, 7}) {
    for (double beta : {15.0, 30.0}) {
      ConeOptions o = ConeOptions::occlusion(beta, splits);
      o.length = 1.3;
      const ConeTracer corrected(p, o);
      o.lateral_variance = false;
      const ConeTracer plain(p, o);
      const double exact = 0.5 * (1.0 + std::exp(-tau * (o.length - corrected.gap())));
      const double with = corrected.transmittance({0, 0, -0.5}, {0, 0, 1});
      const double without = plain.transmittance({0, 0, -0.5}, {0, 0, 1});
      std::printf("half space splits %d beta %.0f: exact %.4f plain %.4f lateral %.4f\n", splits, beta, exact, without, with);
      EXPECT_LT(std::fabs(with - exact), std::fabs(without - exact)) << splits << " " << beta;
      EXPECT_LE(with, exact + 1e-3) << splits << " " << beta;
    }
  }
  // One cone has no spread to estimate from: unchanged.
  ConeOptions one = ConeOptions::occlusion(20.0, 1);
  const double a = ConeTracer(p, one).transmittance({0, 0, -0.5}, {0, 0, 1});
  one.lateral_variance = false;
  EXPECT_EQ(a, ConeTracer(p, one).transmittance({0, 0, -0.5}, {0, 0, 1}));
}

TEST(ConeOccluders, OpaqueBallOnTheAxisIsNeverBrighterThanAnalytic) {
  // Ball of radius 0.3 at distance 0.8: gamma = asin(0.375) = 22.0 deg; exact cosine-weighted
  // fraction 1 - sin^2 gamma / sin^2 beta. The cone model averages extinction over each (sub-)cone
  // section, so a section half covered by an opaque ball is dark, not half lit: the method is
  // biased dark at opaque silhouettes (thesis sec. 3.4, the reason for alpha). Measured and
  // bounded here, not hidden: with splits it never exceeds the exact value, and it brightens with
  // beta. (One cone at 60 deg reads the ball from a level where it is diluted: 0.94 vs 0.81.)
  const double R = 0.3, d = 0.8;
  const ExtinctionPyramid p(grid(97, -1, 1, [&](const Vec3d& x) { return length(x - Vec3d{0, 0, 0.3}) <= R ? 1e4 : 0.0; }));
  for (int splits : {1, 3, 7}) {
    double previous = -1;
    for (double beta : {25.0, 35.0, 45.0, 60.0}) {
      const double want = cone_past_ball(std::asin(R / d), beta * kPi / 180);
      const double got = trace(p, beta, splits);
      std::printf("ball splits %d beta %.0f: exact %.4f cone %.4f error %+.4f\n", splits, beta, want, got, got - want);
      if (splits > 1) EXPECT_LE(got, want + 0.02);
      EXPECT_GE(got, previous - 1e-9);
      previous = got;
    }
  }
  // Inside the ball's shadow cone (gamma >= beta) nothing gets through.
  EXPECT_LT(trace(p, 15.0, 7), 0.01);
}

}  // namespace
}  // namespace penumbra::occlusion_test
