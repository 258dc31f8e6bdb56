// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/extinction_table.h -- exact integral of extinction along a linear segment
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "penumbra/render/transfer_function.h"

namespace penumbra::render::lighting {

/// The transfer function's extinction tau(s), cut at its breakpoints into pieces where it is
/// exactly linear in s (the end pieces are constant). Along a segment where the scalar runs
/// linearly from s0 to s1, tau is piecewise linear in the distance, so the trapezoid rule on each
/// piece is exact: the optical depth has no discretisation error. NaN scalars have no extinction.
class ExtinctionTable {
public:
  ExtinctionTable() = default;
  explicit ExtinctionTable(const TransferFunction& tf) {
    m_x = tf.breakpoints();
    const std::size_t n = m_x.size();
    m_a.assign(n + 1, 0.0);
    m_b.assign(n + 1, 0.0);
    for (std::size_t p = 0; p <= n; ++p) {
      if (p == 0 || p == n) {
        m_a[p] = tf.extinction(p == 0 ? -HUGE_VAL : HUGE_VAL);
        continue;
      }
      // Two samples strictly inside the piece fit its line exactly and ignore a step (repeated
      // control point) at either end.
      const double lo = m_x[p - 1], hi = m_x[p];
      const double s0 = lo + 0.25 * (hi - lo), s1 = lo + 0.75 * (hi - lo);
      m_b[p] = (tf.extinction(s1) - tf.extinction(s0)) / (s1 - s0);
      m_a[p] = tf.extinction(s0) - m_b[p] * s0;
    }
  }

  int piece(double s) const { return static_cast<int>(std::upper_bound(m_x.begin(), m_x.end(), s) - m_x.begin()); }
  /// The pieces, for uploads: piece p (0 .. breakpoints().size(), p between breakpoints p - 1 and
  /// p) is tau(s) = max(0, intercept(p) + slope(p) s).
  const std::vector<double>& breakpoints() const { return m_x; }
  double intercept(std::size_t p) const { return m_a[p]; }
  double slope(std::size_t p) const { return m_b[p]; }
  /// piece(s), checking `hint` first: along a walk the scalar is continuous, so a segment
  /// usually starts in the piece where the previous one ended.
  int piece(double s, int hint) const {
    const auto h = static_cast<std::size_t>(hint);
    if (hint >= 0 && h <= m_x.size() && (h == 0 || m_x[h - 1] <= s) && (h == m_x.size() || s < m_x[h])) return hint;
    return piece(s);
  }

  double tau(double s) const {
    if (std::isnan(s)) return 0.0;
    const auto p = static_cast<std::size_t>(piece(s));
    return std::max(0.0, m_a[p] + m_b[p] * s);
  }

  /// Integral of tau over a segment of `length` whose scalar runs linearly from s0 to s1.
  /// `hint` (optional): a guess of s0's piece, updated to s1's.
  double integral(double s0, double s1, double length, int* hint = nullptr) const {
    if (!(length > 0.0) || std::isnan(s0) || std::isnan(s1)) return 0.0;
    const int p0 = hint ? piece(s0, *hint) : piece(s0);
    const int p1 = hint ? piece(s1, p0) : piece(s1);
    if (hint) *hint = p1;
    if (p0 == p1) return 0.5 * (at(p0, s0) + at(p0, s1)) * length;
    const int step = p1 > p0 ? 1 : -1;
    const double inv_ds = 1.0 / (s1 - s0);
    double sa = s0, fa = 0.0, sum = 0.0;
    for (int p = p0;; p += step) {
      const bool last = p == p1;
      const double sb = last ? s1 : m_x[static_cast<std::size_t>(step > 0 ? p : p - 1)];
      const double fb = last ? 1.0 : (sb - s0) * inv_ds;
      sum += 0.5 * (at(p, sa) + at(p, sb)) * (fb - fa);
      if (last) break;
      sa = sb;
      fa = fb;
    }
    return sum * length;
  }

private:
  double at(int p, double s) const {
    const auto q = static_cast<std::size_t>(p);
    return std::max(0.0, m_a[q] + m_b[q] * s);
  }
  std::vector<double> m_x, m_a, m_b;
};

}  // namespace penumbra::render::lighting
