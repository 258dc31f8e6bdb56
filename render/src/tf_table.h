// SPDX-License-Identifier: BSD-3-Clause
// render/src/tf_table.h -- transfer function as linear pieces, for exact segment integration
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "penumbra/render/transfer_function.h"
#include "segment_integral.h"

namespace penumbra::render::detail {

/// Running front-to-back composite of one ray.
struct Composite {
  double rgb[3] = {0, 0, 0};  ///< premultiplied colour
  double transmittance = 1.0;
  double optical_depth = 0.0;
};

/// A factor on the emitted colour that runs linearly from `front` to `back` along a segment
/// (shading: the light field times the Phong factor; see penumbra/render/shading.h).
struct Modulation {
  double front[3], back[3];
  double at(int c, double fraction) const { return front[c] + (back[c] - front[c]) * fraction; }
};

/// The transfer function cut at its breakpoints x_0 < ... < x_{n-1} into n + 1 pieces: piece p
/// covers [x_{p-1}, x_p] (pieces 0 and n are the clamped ends), where extinction and colour are
/// exactly linear in the scalar: tau(s) = tau0[p] + tau1[p] s, likewise colour.
class TfTable {
public:
  explicit TfTable(const TransferFunction& tf) {
    m_x = tf.breakpoints();
    const std::size_t n = m_x.size();
    // Bounds of piece p at p + 1; "piece" -1 (NaN) at 0 holds nothing.
    m_lower.assign(n + 2, HUGE_VAL);
    m_upper.assign(n + 2, -HUGE_VAL);
    for (std::size_t p = 0; p <= n; ++p) {
      m_lower[p + 1] = p == 0 ? -HUGE_VAL : m_x[p - 1];
      m_upper[p + 1] = p == n ? HUGE_VAL : m_x[p];
    }
    m_pieces.resize(n + 1);
    for (std::size_t p = 0; p <= n; ++p) {
      Piece& q = m_pieces[p];
      if (p == 0 || p == n) {  // clamped ends: constant
        const double s = p == 0 ? -HUGE_VAL : HUGE_VAL;
        q.tau0 = tf.extinction(s);
        const Vec3d c = tf.color(s);
        for (int i = 0; i < 3; ++i) q.col0[i] = c[i];
      } else {
        // Fit the line through two samples strictly inside the piece: exact because the
        // function is linear there, and blind to steps (repeated x) at the piece's ends.
        const double lo = m_x[p - 1], hi = m_x[p];
        const double s0 = lo + 0.25 * (hi - lo), s1 = lo + 0.75 * (hi - lo);
        const double w = 1.0 / (s1 - s0);
        q.tau1 = (tf.extinction(s1) - tf.extinction(s0)) * w;
        q.tau0 = tf.extinction(s0) - q.tau1 * s0;
        const Vec3d c0 = tf.color(s0), c1 = tf.color(s1);
        for (int i = 0; i < 3; ++i) {
          q.col1[i] = (c1[i] - c0[i]) * w;
          q.col0[i] = c0[i] - q.col1[i] * s0;
        }
      }
      const double lo = p == 0 ? m_x[0] : m_x[p - 1], hi = p == n ? m_x[n - 1] : m_x[p];
      q.empty = q.tau0 + q.tau1 * lo <= 0.0 && q.tau0 + q.tau1 * hi <= 0.0;
    }
  }

  /// Piece holding s (s not NaN): the number of breakpoints <= s.
  int piece(double s) const {
    return static_cast<int>(std::upper_bound(m_x.begin(), m_x.end(), s) - m_x.begin());
  }

  /// The piece of s, -1 for NaN (a point with no data).
  int piece_or_nan(double s) const { return std::isnan(s) ? -1 : piece(s); }

  /// piece_or_nan(s), checking the piece `hint` (the previous sample's, usually the
  /// same; -1 allowed) first: two comparisons with the hint's bounds, which are -inf and +inf
  /// at the ends and hold no s for hint -1, so no case is special.
  int piece_near(double s, int hint) const {
    const auto h = static_cast<std::size_t>(hint + 1);
    if (s >= m_lower[h] && s < m_upper[h]) return hint;
    return piece_or_nan(s);
  }

  /// True when the transfer function has zero extinction over the whole scalar range [lo, hi].
  bool empty_range(double lo, double hi) const {
    const int p0 = piece(lo), p1 = piece(hi);
    for (int p = p0; p <= p1; ++p)
      if (!m_pieces[static_cast<std::size_t>(p)].empty) return false;
    return true;
  }

  /// True when piece p has zero extinction throughout.
  bool piece_empty(int p) const { return m_pieces[static_cast<std::size_t>(p)].empty; }

  /// Whether a segment from piece p0 to piece p1 (-1: a NaN end) can add anything: not with a
  /// NaN end (a cell with no data) nor within one piece of zero extinction, skipped cheaply.
  bool emits(int p0, int p1) const { return p0 >= 0 && p1 >= 0 && !(p0 == p1 && piece_empty(p0)); }

  /// Composites the segment of `length` whose scalar runs linearly from s0 (front) to s1
  /// (back) onto `acc`, exactly (see segment_integral.h). NaN ends make the segment empty.
  void integrate(double s0, double s1, double length, Composite& acc) const {
    if (std::isnan(s0) || std::isnan(s1)) return;
    integrate(s0, piece(s0), s1, piece(s1), length, acc);
  }

  /// As above with the pieces of s0 and s1 already known (neither s is NaN), the emitted colour
  /// optionally multiplied by `mod`.
  [[gnu::always_inline]] inline void integrate(double s0, int p0, double s1, int p1, double length, Composite& acc,
                                               const Modulation* mod = nullptr) const {
    if (!(length > 0.0)) return;
    if (p0 == p1) {
      integrate_in_piece(m_pieces[static_cast<std::size_t>(p0)], s0, s1, length, acc, mod, 0.0, 1.0);
      return;
    }
    // Cut at every breakpoint between s0 and s1; the distance is linear in the scalar.
    const int step = p1 > p0 ? 1 : -1;
    const double inv_ds = 1.0 / (s1 - s0);
    double sa = s0, fa = 0.0;
    for (int p = p0;; p += step) {
      const bool last = p == p1;
      const double sb = last ? s1 : m_x[static_cast<std::size_t>(step > 0 ? p : p - 1)];
      const double fb = last ? 1.0 : (sb - s0) * inv_ds;
      integrate_in_piece(m_pieces[static_cast<std::size_t>(p)], sa, sb, (fb - fa) * length, acc, mod, fa, fb);
      if (last) break;
      sa = sb;
      fa = fb;
    }
  }

private:
  struct Piece {
    double tau0 = 0, tau1 = 0, col0[3] = {0, 0, 0}, col1[3] = {0, 0, 0};
    bool empty = true;
  };

  // [fa, fb]: where the piece lies along the whole segment, for the modulation.
  // Always inlined: it is the walk's innermost work, and the unmodulated call sites fold the
  // modulation away.
  [[gnu::always_inline]] static inline void integrate_in_piece(const Piece& q, double sa, double sb, double length,
                                                               Composite& acc, const Modulation* mod, double fa,
                                                               double fb) {
    if (q.empty || !(length > 0.0)) return;
    const double a = std::max(0.0, q.tau0 + q.tau1 * sa) * length;
    const double b = std::max(0.0, q.tau0 + q.tau1 * sb) * length;
    if (a == 0.0 && b == 0.0) return;
    double cf[3] = {q.col0[0] + q.col1[0] * sa, q.col0[1] + q.col1[1] * sa, q.col0[2] + q.col1[2] * sa};
    double cb[3] = {q.col0[0] + q.col1[0] * sb, q.col0[1] + q.col1[1] * sb, q.col0[2] + q.col1[2] * sb};
    if (mod != nullptr)
      for (int c = 0; c < 3; ++c) {
        cf[c] *= mod->at(c, fa);
        cb[c] *= mod->at(c, fb);
      }
    const PieceResult r = integrate_piece(a, b, cf, cb);
    for (int c = 0; c < 3; ++c) acc.rgb[c] += acc.transmittance * r.rgb[c];
    acc.transmittance *= r.transmittance;
    acc.optical_depth += 0.5 * (a + b);
  }

  std::vector<double> m_x;
  std::vector<double> m_lower, m_upper;  // piece_near's bounds, piece p at p + 1
  std::vector<Piece> m_pieces;
};

}  // namespace penumbra::render::detail
