// SPDX-License-Identifier: BSD-3-Clause
// compression/src/window_encoder.cpp -- encodes one window: scan it, train codebooks on a
// sample, choose the page method, encode with it (stages in encode_stages.h).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "encode_stages.h"
#include "page_methods.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"

namespace penumbra::compression {

namespace {

void require_encodable(const float* steps, std::uint64_t vertex_count, std::uint32_t step_count, const double* times,
                       const CodecParams& params, float bound_abs) {
  const std::uint32_t W = params.window, K = params.codebook_size;
  require(steps != nullptr && times != nullptr, "encode_window: null data or times");
  require(vertex_count >= 1, "encode_window: vertex_count must be positive");
  require(detail::valid_window(W),
          "encode_window: window must be a multiple of 8 in [8, 1024], got " + std::to_string(W));
  require(detail::valid_codebook_size(K), "encode_window: codebook_size must be 2..256, got " + std::to_string(K));
  require(step_count >= 1 && step_count <= W, "encode_window: step_count must be 1..window, got " +
                                                  std::to_string(step_count));
  require(std::isfinite(bound_abs) && bound_abs >= 0.f,
          "encode_window: bound must be finite and >= 0, got " + std::to_string(bound_abs));
  require(params.training_sample >= 1, "encode_window: training_sample must be positive");
}

/// The page's shape and range, before any method's contents.
EncodedPage page_header(const detail::Window& win, const double* times, std::uint64_t first_step,
                        std::uint32_t codebook_size, const detail::WindowScan& scan) {
  EncodedPage page;
  page.first_step = first_step;
  page.step_count = win.steps;
  page.window = win.width;
  page.codebook_size = codebook_size;
  page.vertex_count = win.n_vertices;
  page.times.assign(times, times + win.steps);
  page.value_min = scan.value_min;
  page.value_max = scan.value_max;
  return page;
}

/// Records the method and why it was chosen.
void record_choice(EncodedPage& page, const detail::MethodChoice& c) {
  page.method = c.method;
  page.bound = c.method == PageMethod::vq || c.method == PageMethod::vq_aligned ? 0.f : c.bound;
  page.sample_snr_db = float(std::min(c.snr_db, 1e30));
  page.vq_bytes_estimate = float(c.vq_estimate);
  page.predictive_bytes_estimate = float(c.predictive_estimate);
}

void encode_with_chosen_method(EncodedPage& page, const detail::Window& win, const detail::Quantised16& means,
                               detail::Training& training, const detail::MethodChoice& c, const CodecParams& params) {
  switch (c.method) {
    case PageMethod::vq:
    case PageMethod::vq_residual:
      return detail::encode_vq_page(page, win, means, std::move(training.plain), c, params.search_candidates);
    case PageMethod::vq_aligned:
    case PageMethod::vq_aligned_residual:
      return detail::encode_aligned_page(page, win, training.frames, training.aligned, c);
    case PageMethod::predictive:
      return detail::encode_predictive_page(page, win, c);
    case PageMethod::predictive_lanes:
      return detail::encode_predictive_lanes_page(page, win, c);
  }
}

}  // namespace

double resolve_bound(const ErrorBound& bound, double value_min, double value_max) {
  switch (bound.kind) {
    case BoundKind::none:
      return 0;
    case BoundKind::absolute:
      return bound.value;
    case BoundKind::range_relative: {
      // Halves first: the range of values near DBL_MAX overflows.
      const double b = 2 * bound.value * (value_max / 2 - value_min / 2);
      // A constant field has no range; hold it (nearly) exactly rather than not at all.
      return std::max(b, std::numeric_limits<double>::denorm_min());
    }
  }
  return 0;
}

EncodedPage encode_window(const float* steps, std::uint64_t vertex_count, std::uint32_t step_count,
                          const double* times, std::uint64_t first_step, const CodecParams& params, float bound_abs,
                          WarmStart* warm, WindowStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  require_encodable(steps, vertex_count, step_count, times, params, bound_abs);
  const detail::Window win{steps, vertex_count, step_count, params.window, params.window / 8};

  const detail::WindowScan scan = detail::scan_window(win, first_step);
  EncodedPage page = page_header(win, times, first_step, params.codebook_size, scan);
  const detail::Quantised16 means = detail::quantise_16bit(scan.mean);
  const detail::TrainingSample sample = detail::draw_training_sample(win, means.values, params, first_step);
  detail::Training training = detail::train_codebooks(win, sample, params, warm);
  const detail::MethodChoice choice =
      detail::choose_method(win, sample, training, params, scan.value_min, scan.value_max, bound_abs);
  record_choice(page, choice);
  encode_with_chosen_method(page, win, means, training, choice, params);

  if (stats) {
    stats->train_seconds = training.seconds;
    stats->sample_snr_db = choice.snr_db;
    stats->vq_bytes_estimate = std::uint64_t(choice.vq_estimate);
    stats->predictive_bytes_estimate = std::uint64_t(choice.predictive_estimate);
    stats->encode_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return page;
}

}  // namespace penumbra::compression
