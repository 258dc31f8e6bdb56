// SPDX-License-Identifier: BSD-3-Clause
// render/src/segment_integral.cpp -- special functions behind the exact segment integral
#include "segment_integral.h"

#include <numbers>

namespace penumbra::render::detail {

double erfcx(double y) {
  // Below 12 the product loses only ~y^2 * 1e-16 to the rounding of y^2; above, the asymptotic
  // series is used, whose 10th term is below 1e-15 there.
  if (y < 12.0) return std::exp(y * y) * std::erfc(y);
  const double inv2y2 = 1.0 / (2.0 * y * y);
  double term = 1.0, sum = 1.0;
  for (int n = 1; n <= 10; ++n) {
    term *= -(2.0 * n - 1.0) * inv2y2;
    sum += term;
  }
  return sum / (y * std::sqrt(std::numbers::pi));
}

double dawson(double x) {
  if (x < 0.2) {
    // F(x) = sum_n (-1)^n 2^n x^(2n+1) / (2n+1)!!
    double term = x, sum = x;
    const double x2 = x * x;
    for (int n = 1; n < 30 && std::fabs(term) > 1e-18 * std::fabs(sum); ++n) {
      term *= -2.0 * x2 / (2.0 * n + 1.0);
      sum += term;
    }
    return sum;
  }
  if (x > 10.0) {
    // F(x) ~ 1/(2x) sum_n (2n-1)!! / (2x^2)^n; the 12th term is below 1e-16 for x > 10.
    const double inv2x2 = 1.0 / (2.0 * x * x);
    double term = 1.0, sum = 1.0;
    for (int n = 1; n <= 12; ++n) {
      term *= (2.0 * n - 1.0) * inv2x2;
      sum += term;
    }
    return sum / (2.0 * x);
  }
  // Rybicki's sampling-theorem sum (Numerical Recipes 6.10) with step h = 0.2: the aliasing
  // error is exp(-(pi / 2h)^2) ~ 1e-27, and terms stop once exp(-((2i-1) h)^2) < 1e-21.
  constexpr double h = 0.2;
  constexpr int nmax = 18;
  static const auto c = [] {
    struct Table { double v[nmax + 1]; } t{};
    for (int i = 1; i <= nmax; ++i) t.v[i] = std::exp(-((2.0 * i - 1.0) * h) * ((2.0 * i - 1.0) * h));
    return t;
  }();
  const int n0 = 2 * static_cast<int>(0.5 * x / h + 0.5);
  const double xp = x - n0 * h;
  double e1 = std::exp(2.0 * xp * h);
  const double e2 = e1 * e1;
  double d1 = n0 + 1.0, d2 = d1 - 2.0, sum = 0.0;
  for (int i = 1; i <= nmax; ++i, d1 += 2.0, d2 -= 2.0, e1 *= e2) sum += c.v[i] * (e1 / d1 + 1.0 / (d2 * e1));
  return std::exp(-xp * xp) * sum / std::sqrt(std::numbers::pi);
}

double attenuation_integral_general(double a, double b) {
  const double t = std::exp(-0.5 * (a + b));
  if (a == b) return -std::expm1(-a) / a;
  if (b > a) {
    const double k = 0.5 * (b - a), sk = std::sqrt(k);
    return std::sqrt(std::numbers::pi) / (2.0 * sk) * (erfcx(a / (2.0 * sk)) - t * erfcx(b / (2.0 * sk)));
  }
  const double k = 0.5 * (a - b), sk = std::sqrt(k);
  return (dawson(a / (2.0 * sk)) - t * dawson(b / (2.0 * sk))) / sk;
}

}  // namespace penumbra::render::detail
