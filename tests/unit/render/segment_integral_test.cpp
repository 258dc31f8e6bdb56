// SPDX-License-Identifier: BSD-3-Clause
#include "segment_integral.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tf_table.h"

namespace penumbra::render::detail {
namespace {

// Composite Simpson with many panels on a smooth integrand: error ~ h^4 f'''' / 180.
template <class F>
double simpson(F f, double a, double b, int n = 20000) {
  const double h = (b - a) / n;
  double s = f(a) + f(b);
  for (int i = 1; i < n; ++i) s += f(a + i * h) * ((i & 1) ? 4.0 : 2.0);
  return s * h / 3.0;
}

TEST(SegmentIntegral, ZMatchesQuadratureOverWideRange) {
  const double values[] = {0.0, 1e-9, 1e-4, 0.01, 0.1, 0.3, 0.49, 0.51, 0.9, 1.7, 3.0, 10.0, 40.0, 300.0, 5e4};
  for (double a : values)
    for (double b : values) {
      if (a + b == 0) continue;
      // Integrate only up to depth D = 60 (the rest is < 1e-26) so the panels resolve the
      // decay: D(u) = a u + k u^2 reaches 60 at the root below.
      const double k = 0.5 * (b - a);
      const double end =
          k > 0 ? std::min(1.0, 120.0 / (a + std::sqrt(a * a + 240.0 * k))) : std::min(1.0, 120.0 / std::max(a, 1e-300));  // D >= a u / 2 when b < a
      const double expect =
          simpson([&](double u) { return std::exp(-(a * u + 0.5 * (b - a) * u * u)); }, 0.0, end, 200000);
      const double z = attenuation_integral(a, b);
      // Simpson with 2e5 panels is good to ~1e-13 relative here; the closed forms claim 1e-13.
      EXPECT_NEAR(z, expect, 1e-11 * expect) << "a=" << a << " b=" << b;
    }
}

TEST(SegmentIntegral, SeriesAndClosedFormAgreeAtTheSwitch) {
  for (double a : {0.0, 0.05, 0.1, 0.2, 0.24})
    for (double b : {0.0, 0.01, 0.1, 0.3, 0.5}) {
      if (a + b == 0 || a + 0.5 * std::fabs(b - a) > 0.25) continue;
      const double s = attenuation_series<kSeriesOrder>(a, 0.5 * (b - a));  // the series' range
      const double g = attenuation_integral_general(a, b);  // closed form
      EXPECT_NEAR(s, g, 1e-13) << a << " " << b;
    }
}

TEST(SegmentIntegral, SpecialFunctionsMatchDefinitions) {
  for (double x : {0.0, 0.05, 0.19, 0.21, 0.5, 1.0, 2.5, 5.0, 9.9, 10.1, 12.5, 20.0, 25.0, 300.0}) {
    // F(x) = int_0^x exp(-w (2x - w)) dw with w = x - t: no overflow, and the integrand's
    // decay (scale 1/2x) is resolved by integrating only where it exceeds e^-60.
    const double end = std::min(x, 60.0 / std::max(x, 1e-300));
    const double f = simpson([x](double w) { return std::exp(-w * (2.0 * x - w)); }, 0.0, end, 200000);
    EXPECT_NEAR(dawson(x), f, 1e-12 * f) << "x=" << x;
    if (x > 25) continue;
    // Below 26 the direct product is accurate to ~y^2 ulp: a fair check of the asymptotic branch.
    EXPECT_NEAR(erfcx(x), std::exp(x * x) * std::erfc(x), 1e-13 * erfcx(x)) << "x=" << x;
  }
  EXPECT_NEAR(erfcx(1e6) * 1e6 * std::sqrt(3.14159265358979323846), 1.0, 1e-12);
}

// Reference for a segment by brute-force integration of dC = c tau T ds, dT = -tau T ds.
Composite brute(const TransferFunction& tf, double s0, double s1, double len) {
  const int n = 200000;
  const double h = len / n;
  Composite acc;
  double depth = 0;
  auto tau = [&](double x) { return tf.extinction(s0 + (s1 - s0) * x / len); };
  for (int i = 0; i < n; ++i) {
    // Midpoint rule on the emission with exact depth by trapezoids (tau is piecewise linear).
    const double xm = (i + 0.5) * h;
    const double dm = depth + 0.5 * (tau(i * h) + tau(xm)) * 0.5 * h;
    const Vec3d c = tf.color(s0 + (s1 - s0) * xm / len);
    const double w = tau(xm) * std::exp(-dm) * h;
    acc.rgb[0] += c.x * w;
    acc.rgb[1] += c.y * w;
    acc.rgb[2] += c.z * w;
    depth += 0.5 * (tau(i * h) + tau((i + 1) * h)) * h;
  }
  acc.transmittance = std::exp(-depth);
  acc.optical_depth = depth;
  return acc;
}

TEST(TfTable, SegmentAcrossBreakpointsMatchesBruteForce) {
  TransferFunction tf;
  tf.colors = {{0.0, 1, 0, 0}, {0.5, 0, 1, 0}, {1.0, 0, 0, 1}};
  tf.opacities = {{0.1, 0.0}, {0.3, 6.0}, {0.6, 0.5}, {0.9, 3.0}};
  const TfTable table(tf);
  for (const auto& [s0, s1, len] : {std::tuple{-0.2, 1.3, 0.7}, {0.95, 0.05, 1.5}, {0.4, 0.45, 0.2}, {0.7, 0.7, 0.3}}) {
    Composite acc;
    table.integrate(s0, s1, len, acc);
    const Composite ref = brute(tf, s0, s1, len);
    // Midpoint rule with 2e5 steps: error ~ h^2 ~ 1e-11 relative, plus kinks at breakpoints
    // (first-order locally, ~h * jump ~ 1e-5 * 1e-5): 1e-8 is safe.
    EXPECT_NEAR(acc.optical_depth, ref.optical_depth, 1e-8) << s0 << "->" << s1;
    EXPECT_NEAR(acc.transmittance, ref.transmittance, 1e-8);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(acc.rgb[c], ref.rgb[c], 1e-8) << "channel " << c;
  }
}

TEST(TfTable, EmptyRangesAndNanSegments) {
  TransferFunction tf;
  tf.colors = {{0.0, 1, 1, 1}};
  tf.opacities = {{0.0, 0.0}, {0.4, 0.0}, {0.5, 1.0}};
  const TfTable table(tf);
  EXPECT_TRUE(table.empty_range(-3, 0.39));
  EXPECT_FALSE(table.empty_range(0.3, 0.41));
  Composite acc;
  table.integrate(std::nan(""), 0.5, 1.0, acc);
  EXPECT_EQ(acc.transmittance, 1.0);
  table.integrate(-1.0, 0.2, 1.0, acc);
  EXPECT_EQ(acc.optical_depth, 0.0);
}

TEST(SegmentIntegral, SmallExponentPolynomialMatchesExp) {
  // Used for the transmittance of thin segments: within 2 rounding units of exp on its whole
  // domain [0, 0.02], including the switch point.
  for (int i = 0; i <= 2000; ++i) {
    const double x = 0.02 * i / 2000.0;
    EXPECT_NEAR(exp_neg_small(x), std::exp(-x), 4.5e-16) << "x=" << x;
  }
}

}  // namespace
}  // namespace penumbra::render::detail
