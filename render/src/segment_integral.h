// SPDX-License-Identifier: BSD-3-Clause
// render/src/segment_integral.h -- exact emission-absorption integral of one linear segment
//
// Along a segment of length L where extinction tau and colour c are both linear in the
// distance (the scalar is linear in a tet and the transfer function linear between two
// breakpoints), with a = tau_front * L and b = tau_back * L:
//
//   transmittance  T = exp(-(a + b) / 2)
//   colour         C = c_front * (1 - Z) + c_back * (Z - T),   Z(a, b) = int_0^1 exp(-D(u)) du,
//   D(u) = a u + (b - a) u^2 / 2  (the optical depth from the front to fraction u).
//
// This is Moreland & Angel's partial pre-integration identity (their Psi is Z), obtained by
// integrating c(u) D'(u) exp(-D(u)) by parts, with no table: Z is evaluated in closed form.
//   - a + |b - a|/2 <= 0.25: Taylor series of exp(-D) integrated term by term, truncated
//     where the remainder bound (a + |b - a|/2)^(n+1)/(n+1)! is below ~1e-14;
//   - b > a: Z = sqrt(pi) / (2 sqrt(k)) * (erfcx(y_a) - T erfcx(y_b)),  k = (b - a)/2;
//   - b < a: Z = (F(y_a) - T F(y_b)) / sqrt(k),                           k = (a - b)/2;
//   - b = a: Z = (1 - exp(-a)) / a,
// with y_a = a / (2 sqrt(k)), y_b = b / (2 sqrt(k)), erfcx the scaled complementary error
// function and F Dawson's integral (Rybicki's sampling sum). Relative accuracy of Z is about
// 1e-13 (series truncation <= 1e-13, closed forms lose at most ~1 digit to cancellation);
// tests/unit/render/segment_integral_test.cpp checks 1e-11 against quadrature for a, b in
// [0, 5e4]. The fast path never needs a table, so there is no table resolution error.
#pragma once
#include <cmath>

namespace penumbra::render::detail {

/// exp(y^2) * erfc(y) for y >= 0, relative error ~1e-14.
double erfcx(double y);
/// Dawson's integral F(x) = exp(-x^2) int_0^x exp(t^2) dt for x >= 0, relative error ~1e-13.
double dawson(double x);
/// Z(a, b) above by the special-function forms (any a, b >= 0 with a + b > 0).
double attenuation_integral_general(double a, double b);

/// Coefficients of the double Taylor series of Z in a and k = (b - a)/2:
/// Z = sum_n sum_j kSeries[n][j] a^j k^(n-j), from exp(-D) = sum_n (-D)^n / n! with
/// D^n = sum_j C(n,j) a^j k^(n-j) u^(2n-j) and int_0^1 u^m du = 1/(m+1).
inline constexpr int kSeriesOrder = 10;
struct SeriesTable {
  double c[kSeriesOrder + 1][kSeriesOrder + 1] = {};
  constexpr SeriesTable() {
    double fact = 1.0;
    for (int n = 0; n <= kSeriesOrder; ++n) {
      if (n > 0) fact *= n;
      double binom = 1.0;
      for (int j = 0; j <= n; ++j) {
        c[n][j] = ((n & 1) ? -1.0 : 1.0) * binom / (fact * (2 * n - j + 1));
        binom = binom * (n - j) / (j + 1);
      }
    }
  }
};
inline constexpr SeriesTable kSeries{};

template <int N>
inline double attenuation_series(double a, double k) {
  // Horner in a over polynomials in k: sum_j a^j sum_i c[i+j][j] k^i.
  double sum = 0.0;
#pragma GCC unroll 16
  for (int j = N; j >= 0; --j) {
    double inner = 0.0;
#pragma GCC unroll 16
    for (int i = N - j; i >= 0; --i) inner = inner * k + kSeries.c[i + j][j];
    sum = sum * a + inner;
  }
  return sum;
}

/// Z(a, b) for delta = a + |k| > 0.02, k = (b - a) / 2, as attenuation_integral computed them;
/// out of line: thicker segments are rare in a fine mesh, and inlined their series would crowd
/// the walk's hot code.
[[gnu::noinline]] inline double attenuation_integral_thick(double a, double b, double k, double delta) {
  // Order N suffices while delta^(N+1)/(N+1)! < 1e-14.
  if (delta <= 0.08) return attenuation_series<7>(a, k);
  if (delta <= 0.14) return attenuation_series<8>(a, k);
  if (delta <= 0.25) return attenuation_series<kSeriesOrder>(a, k);
  return attenuation_integral_general(a, b);
}

/// Z(a, b) above for a, b >= 0: the series, truncated after order N where the remainder bound
/// delta^(N+1)/(N+1)! (delta = a + |k| >= max D) is below ~1e-15, while delta <= 0.25 (the
/// common case in a fine mesh, and the one where the closed forms cancel); closed forms beyond.
inline double attenuation_integral(double a, double b) {
  const double k = 0.5 * (b - a);
  const double delta = a + std::fabs(k);
  // Order N suffices while delta^(N+1)/(N+1)! < 1e-14.
  if (delta <= 0.02) {
    if (delta <= 1.2e-3) return attenuation_series<3>(a, k);
    return attenuation_series<5>(a, k);
  }
  return attenuation_integral_thick(a, b, k, delta);
}

/// Colour and transmittance of one linear piece, as above. `cf`/`cb` are front/back colours.
struct PieceResult {
  double rgb[3];
  double transmittance;
};
/// exp(-x) for 0 <= x <= 0.02 by its Taylor polynomial of degree 6: the remainder is below
/// x^7/7! <= 2.6e-16, under one rounding unit, at a fifth of the cost of a call to exp. Most
/// segments of a fine mesh are this thin.
inline double exp_neg_small(double x) {
  // Estrin's scheme: the powers and the pairs of terms evaluate side by side, about half the
  // latency of Horner's chain of six dependent multiply-adds on the walk's critical path.
  const double x2 = x * x, x4 = x2 * x2;
  const double low = 1.0 - x, mid = 1.0 / 2 - x * (1.0 / 6), high = (1.0 / 24 - x * (1.0 / 120)) + x2 * (1.0 / 720);
  return (low + x2 * mid) + x4 * high;
}

inline PieceResult integrate_piece(double a, double b, const double cf[3], const double cb[3]) {
  const double half_depth = 0.5 * (a + b);
  const double t = half_depth <= 0.02 ? exp_neg_small(half_depth) : std::exp(-half_depth);
  const double z = attenuation_integral(a, b);
  const double wf = 1.0 - z, wb = z - t;
  return {{cf[0] * wf + cb[0] * wb, cf[1] * wf + cb[1] * wb, cf[2] * wf + cb[2] * wb}, t};
}

}  // namespace penumbra::render::detail
