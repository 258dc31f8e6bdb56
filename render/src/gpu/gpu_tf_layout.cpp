// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/gpu_tf_layout.cpp -- transfer-function pieces and series coefficients for the shader
#include "gpu_tf_layout.h"

#include <cmath>

#include "segment_integral.h"

namespace penumbra::render::gpu {

GpuTfLayout build_gpu_tf_layout(const TransferFunction& tf, double length_scale) {
  GpuTfLayout out;
  const std::vector<double> x = tf.breakpoints();
  const std::size_t n = x.size();
  out.breakpoint_count = static_cast<int>(n);
  out.data.assign((n + 1) * kTfPieceFloats + n, 0.0f);
  for (std::size_t p = 0; p <= n; ++p) {
    float* q = &out.data[p * kTfPieceFloats];
    double s_ref = 0, tau_ref = 0, tau1 = 0, col_ref[3] = {0, 0, 0}, col1[3] = {0, 0, 0};
    if (p == 0 || p == n) {  // clamped ends: constant
      const double s = p == 0 ? -HUGE_VAL : HUGE_VAL;
      tau_ref = tf.extinction(s);
      const Vec3d c = tf.color(s);
      for (int i = 0; i < 3; ++i) col_ref[i] = c[i];
    } else {
      // As the CPU table: the line through two samples strictly inside the piece, blind to steps
      // (repeated x) at its ends; then evaluated at the float32 lower breakpoint.
      const double lo = x[p - 1], hi = x[p];
      const double s0 = lo + 0.25 * (hi - lo), s1 = lo + 0.75 * (hi - lo);
      const double w = 1.0 / (s1 - s0);
      s_ref = static_cast<float>(lo);
      tau1 = (tf.extinction(s1) - tf.extinction(s0)) * w;
      tau_ref = tf.extinction(s0) + tau1 * (s_ref - s0);
      const Vec3d c0 = tf.color(s0), c1 = tf.color(s1);
      for (int i = 0; i < 3; ++i) {
        col1[i] = (c1[i] - c0[i]) * w;
        col_ref[i] = c0[i] + col1[i] * (s_ref - s0);
      }
    }
    const double lo = p == 0 ? x[0] : x[p - 1], hi = p == n ? x[n - 1] : x[p];
    const bool empty = tau_ref + tau1 * (lo - s_ref) <= 0.0 && tau_ref + tau1 * (hi - s_ref) <= 0.0;
    q[0] = static_cast<float>(s_ref);
    q[1] = static_cast<float>(tau_ref * length_scale);
    q[2] = static_cast<float>(tau1 * length_scale);
    q[3] = empty ? 1.0f : 0.0f;
    for (int i = 0; i < 3; ++i) {
      q[4 + i] = static_cast<float>(col_ref[i]);
      q[8 + i] = static_cast<float>(col1[i]);
    }
  }
  for (std::size_t i = 0; i < n; ++i) out.data[(n + 1) * kTfPieceFloats + i] = static_cast<float>(x[i]);
  return out;
}

std::vector<float> one_minus_z_series() {
  std::vector<float> c(64, 0.0f);
  for (int n = 1; n <= 7; ++n)
    for (int j = 0; j <= n; ++j) c[static_cast<std::size_t>(n * 8 + j)] = static_cast<float>(-detail::kSeries.c[n][j]);
  return c;
}

}  // namespace penumbra::render::gpu
