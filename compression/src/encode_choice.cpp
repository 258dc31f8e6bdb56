// SPDX-License-Identifier: BSD-3-Clause
// compression/src/encode_choice.cpp -- which method stores the window: VQ, VQ with a residual
// that holds the bound, or the predictive coder, judged on the training sample.
#include <algorithm>
#include <cmath>

#include "encode_sections.h"
#include "encode_stages.h"

namespace penumbra::compression::detail {

namespace {

/// Variance of the sample's real steps.
double sample_variance(const Window& win, const TrainingSample& sample) {
  const std::uint32_t W = win.width, n = win.steps;
  double sum = 0, sum2 = 0;
  for (std::uint64_t i = 0; i < sample.size(); ++i)
    for (std::uint32_t t = 0; t < n; ++t) {
      const double x = sample.series[i * W + t];
      sum += x;
      sum2 += x * x;
    }
  const double count = double(sample.size()) * n;
  return std::max(0.0, sum2 / count - (sum / count) * (sum / count));
}

double vq_snr_db(const Window& win, const TrainingSample& sample, double vq_mse) {
  return vq_mse > 0 ? 10.0 * std::log10(std::max(sample_variance(win, sample), 1e-300) / vq_mse) : 300.0;
}

/// Bytes of the VQ records and codebooks, before any residual.
double vq_base_bytes(const Window& win, const Training& training, std::uint32_t K) {
  const double codebook_bytes =
      training.use_aligned ? double(K) * training.frames.dim * 2 : double(K) * (8 + win.width) * 4;
  return double(win.n_vertices) * 4 + codebook_bytes;
}

/// Bits of k_0 for values in [lo, value_max] at `step`.
std::uint32_t first_value_width(float lo, float value_max, float step) {
  const double levels = std::ceil((double(value_max) - lo) / step) + 1;
  return levels >= double(1u << 30) ? 31u : std::max(1u, bit_width(std::uint32_t(levels)));
}

/// Adds the residual's bytes to c.vq_estimate and sets c.predictive_estimate: both coders run
/// over the sample without writing, and their mean bits per vertex are scaled to the window.
void estimate_coded_bytes(const Window& win, const TrainingSample& sample, const Training& training, MethodChoice& c) {
  const std::uint32_t W = win.width, n = win.steps;
  const std::uint64_t S = sample.size();
  std::vector<float> base(W);
  std::vector<std::uint32_t> z(W);
  std::vector<std::int64_t> k(W);
  double vq_bits = 0, pred_bits = 0;
  for (std::uint64_t i = 0; i < S; ++i) {
    const float* x = sample.series_of(i, W);
    training.sample_series(win, sample, i, base.data());
    vq_bits += double(encode_residual_section(x, n, base.data(), c.quantiser.step, c.bound, nullptr, z.data()).bits);
    pred_bits += double(encode_predictive_section(x, n, c.quantiser, c.bound, nullptr, k.data(), z.data()).bits);
  }
  const double per_vertex_overhead = 0.5 + 8.0 / kGroup;  // width nibble + group offset
  const double N = double(win.n_vertices);
  c.vq_estimate += N * (per_vertex_overhead + vq_bits / double(S) / 8);
  c.predictive_estimate = N * (per_vertex_overhead + pred_bits / double(S) / 8);
}

/// The aligned counterpart of a plain VQ method.
PageMethod aligned_method(PageMethod m) {
  if (m == PageMethod::vq) return PageMethod::vq_aligned;
  if (m == PageMethod::vq_residual) return PageMethod::vq_aligned_residual;
  return m;
}

}  // namespace

MethodChoice choose_method(const Window& win, const TrainingSample& sample, const Training& training,
                           const CodecParams& params, float value_min, float value_max, float bound_abs) {
  const double vq_mse = training.vq_mse();
  MethodChoice c;
  c.snr_db = vq_snr_db(win, sample, vq_mse);
  c.bound = bound_abs;
  c.method = c.bound > 0 ? PageMethod::vq_residual : PageMethod::vq;
  if (c.bound == 0 && c.snr_db < params.min_vq_snr_db && vq_mse > 0) {
    // VQ-poor and unbounded: a predictive coder at VQ's own RMS error is never less accurate.
    c.bound = float(std::sqrt(vq_mse));
    c.method = PageMethod::predictive;
  }
  c.quantiser.step = 2.f * c.bound;
  c.quantiser.lo = value_min;
  c.vq_estimate = vq_base_bytes(win, training, params.codebook_size);
  if (c.bound > 0) {
    c.quantiser.first_width = first_value_width(value_min, value_max, c.quantiser.step);
    estimate_coded_bytes(win, sample, training, c);
    if (c.method == PageMethod::vq_residual && c.predictive_estimate < c.vq_estimate) c.method = PageMethod::predictive;
  }
  // The estimate above is of per-vertex sections; lane blocks come out smaller where a run's
  // first steps jump (their first step has a width of its own) and about the same elsewhere.
  if (c.method == PageMethod::predictive && params.predictive_lanes) c.method = PageMethod::predictive_lanes;
  if (training.use_aligned) c.method = aligned_method(c.method);
  return c;
}

}  // namespace penumbra::compression::detail
