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
// function and F Dawson's integral. Relative accuracy of Z is about 1e-13 over a, b in
// [0, 1e6] (tests/unit/render/segment_integral_test.cpp checks it against quadrature).
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
  double ap[N + 1], kp[N + 1];
  ap[0] = kp[0] = 1.0;
  for (int i = 1; i <= N; ++i) {
    ap[i] = ap[i - 1] * a;
    kp[i] = kp[i - 1] * k;
  }
  double sum = 0.0;
  for (int n = N; n >= 0; --n) {
    double inner = 0.0;
    for (int j = 0; j <= n; ++j) inner += kSeries.c[n][j] * ap[j] * kp[n - j];
    sum += inner;
  }
  return sum;
}

/// Z(a, b) above for a, b >= 0: the series, truncated after order N where the remainder bound
/// delta^(N+1)/(N+1)! (delta = a + |k| >= max D) is below ~1e-15, while delta <= 0.25 (the
/// common case in a fine mesh, and the one where the closed forms cancel); closed forms beyond.
inline double attenuation_integral(double a, double b) {
  const double k = 0.5 * (b - a);
  const double delta = a + std::fabs(k);
  if (delta <= 1e-4) return attenuation_series<3>(a, k);
  if (delta <= 5e-3) return attenuation_series<5>(a, k);
  if (delta <= 0.05) return attenuation_series<7>(a, k);
  if (delta <= 0.25) return attenuation_series<kSeriesOrder>(a, k);
  return attenuation_integral_general(a, b);
}

/// Colour and transmittance of one linear piece, as above. `cf`/`cb` are front/back colours.
struct PieceResult {
  double rgb[3];
  double transmittance;
};
inline PieceResult integrate_piece(double a, double b, const double cf[3], const double cb[3]) {
  const double t = std::exp(-0.5 * (a + b));
  const double z = attenuation_integral(a, b);
  const double wf = 1.0 - z, wb = z - t;
  return {{cf[0] * wf + cb[0] * wb, cf[1] * wf + cb[1] * wb, cf[2] * wf + cb[2] * wb}, t};
}

}  // namespace penumbra::render::detail
