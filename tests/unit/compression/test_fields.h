// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/test_fields.h -- small synthetic time-varying fields, step-major, and the
// pages encoded from them.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "penumbra/compression/codec_params.h"
#include "penumbra/compression/window_codec.h"

namespace penumbra::compression::testing {

/// Vertices on a jittered 1D-ish line in [0,1]^2; field[t * n + v].
struct SyntheticField {
  std::uint64_t vertices;
  std::uint32_t steps;
  std::vector<float> values;
  std::vector<double> times;
  float range() const {
    float lo = values[0], hi = values[0];
    for (float x : values) lo = std::min(lo, x), hi = std::max(hi, x);
    return hi - lo;
  }
};

inline void vertex_position(std::uint64_t v, std::uint64_t n, double& x, double& y) {
  std::mt19937_64 rng(v * 7919 + 17);
  std::uniform_real_distribution<double> u(0, 1);
  x = u(rng);
  y = u(rng);
  (void)n;
}

/// Gaussian blobs drifting across the unit square: smooth in time at every vertex.
inline SyntheticField smooth_blobs(std::uint64_t n, std::uint32_t steps) {
  SyntheticField f{n, steps, std::vector<float>(n * steps), std::vector<double>(steps)};
  for (std::uint32_t t = 0; t < steps; ++t) {
    f.times[t] = 0.1 * t;
    const double s = double(t) / steps;
    for (std::uint64_t v = 0; v < n; ++v) {
      double x, y;
      vertex_position(v, n, x, y);
      double val = 0;
      const double cx[3] = {0.2 + 0.5 * s, 0.8 - 0.4 * s, 0.5}, cy[3] = {0.3, 0.6 + 0.2 * s, 0.2 + 0.6 * s};
      for (int b = 0; b < 3; ++b) {
        const double r2 = (x - cx[b]) * (x - cx[b]) + (y - cy[b]) * (y - cy[b]);
        val += (1.0 + 0.3 * b) * std::exp(-r2 / 0.02);
      }
      f.values[t * n + v] = float(val);
    }
  }
  return f;
}

/// A front x = 0.2 + 0.6 s travelling across the domain with a unit jump, plus a gentle slope.
inline SyntheticField shock_front(std::uint64_t n, std::uint32_t steps) {
  SyntheticField f{n, steps, std::vector<float>(n * steps), std::vector<double>(steps)};
  for (std::uint32_t t = 0; t < steps; ++t) {
    f.times[t] = t;
    const double front = 0.1 + 0.8 * double(t) / steps;
    for (std::uint64_t v = 0; v < n; ++v) {
      double x, y;
      vertex_position(v, n, x, y);
      f.values[t * n + v] = float((x < front ? 2.0 : 1.0) + 0.2 * y);
    }
  }
  return f;
}

/// A blast-like front: ahead of it a level that varies in space; at its arrival (a different,
/// non-integer time at every vertex) a jump of about 1.5 that relaxes exponentially. One
/// plain codebook entry per arrival step would be needed; aligned at the jump, one shape.
inline SyntheticField relaxing_front(std::uint64_t n, std::uint32_t steps) {
  SyntheticField f{n, steps, std::vector<float>(n * steps), std::vector<double>(steps)};
  for (std::uint32_t t = 0; t < steps; ++t) {
    f.times[t] = t;
    const double s = double(t) / steps, front = -0.05 + 1.1 * s, strength = 1.5 / (1 + 0.5 * s);
    for (std::uint64_t v = 0; v < n; ++v) {
      double x, y;
      vertex_position(v, n, x, y);
      const double ahead = 1.0 + 0.2 * y;
      f.values[t * n + v] = float(x < front ? ahead + strength * std::exp(-(front - x) / 0.2) : ahead);
    }
  }
  return f;
}

/// Independent noise at every value: nothing for VQ to exploit.
inline SyntheticField white_noise(std::uint64_t n, std::uint32_t steps, std::uint64_t seed = 5) {
  SyntheticField f{n, steps, std::vector<float>(n * steps), std::vector<double>(steps)};
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> g(0.f, 1.f);
  for (std::uint32_t t = 0; t < steps; ++t) f.times[t] = t;
  for (auto& x : f.values) x = g(rng);
  return f;
}

/// Outliers inside the field's range (so the bound and the codebooks keep their scale): a
/// spike at one step makes a patched section (one exception), a vertex jumping between the
/// extremes at every step makes a raw one under a tight bound (most of its values wider than
/// the 15 bits a packed slot holds).
inline void add_outliers(SyntheticField& f) {
  const auto [lo, hi] = std::minmax_element(f.values.begin(), f.values.end());
  const float low = *lo, high = *hi;
  for (std::uint64_t v = 3; v < f.vertices; v += 11) f.values[(v % f.steps) * f.vertices + v] = v % 2 ? low : high;
  for (std::uint64_t v = 7; v < f.vertices; v += 97)
    for (std::uint32_t t = 0; t < f.steps; ++t) f.values[std::uint64_t(t) * f.vertices + v] = t % 2 ? low : high;
}

/// Four oscillating sources (periods of 8 to 13 steps) with a spatial fall-off: a few temporal
/// shapes shared by many vertices, which VQ captures and a predictor does not.
inline SyntheticField oscillating_sources(std::uint64_t n, std::uint32_t steps) {
  SyntheticField f{n, steps, std::vector<float>(n * steps), std::vector<double>(steps)};
  const double period[4] = {8, 9.5, 11, 13}, sx[4] = {0.2, 0.8, 0.5, 0.3}, sy[4] = {0.3, 0.7, 0.1, 0.9};
  for (std::uint32_t t = 0; t < steps; ++t) {
    f.times[t] = t;
    for (std::uint64_t v = 0; v < n; ++v) {
      double x, y, value = 0;
      vertex_position(v, n, x, y);
      for (int s = 0; s < 4; ++s) {
        const double r2 = (x - sx[s]) * (x - sx[s]) + (y - sy[s]) * (y - sy[s]);
        value += std::exp(-r2 / 0.05) * std::sin(2 * 3.14159265358979 * t / period[s] + s);
      }
      f.values[std::uint64_t(t) * n + v] = float(value);
    }
  }
  return f;
}

/// Codebooks a few thousand vertices fill: plain VQ with 16 entries (no aligned codebook), and
/// shift-aligned VQ with 32.
inline CodecParams small_plain_codebooks() {
  CodecParams p;
  p.aligned = false;
  p.codebook_size = 16;
  return p;
}
inline CodecParams small_aligned_codebooks() {
  CodecParams p;
  p.codebook_size = 32;
  return p;
}

/// encode_window over steps [first, first + count) of f.
inline EncodedPage encode(const SyntheticField& f, std::uint32_t first, std::uint32_t count, const CodecParams& p,
                          float bound = 0, WarmStart* warm = nullptr) {
  return encode_window(f.values.data() + std::uint64_t(first) * f.vertices, f.vertices, count, f.times.data() + first,
                       first, p, bound, warm);
}

/// The first `count` steps of f as a page that cursors can hold.
inline std::shared_ptr<const EncodedPage> shared_page(const SyntheticField& f, std::uint32_t count,
                                                      const CodecParams& p, float bound) {
  return std::make_shared<const EncodedPage>(encode(f, 0, count, p, bound));
}

}  // namespace penumbra::compression::testing
