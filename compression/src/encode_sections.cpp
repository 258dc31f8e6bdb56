// SPDX-License-Identifier: BSD-3-Clause
// compression/src/encode_sections.cpp -- one vertex's section of a page's BitBlocks, encoded.
#include "encode_sections.h"

#include <cmath>

#include "predictive_layout.h"
#include "round_to_integer.h"
#include "value_layout.h"

namespace penumbra::compression::detail {

namespace {

SectionCost write_raw(const float* x, std::uint32_t steps, BitWriter* writer) {
  if (writer)
    for (std::uint32_t t = 0; t < steps; ++t) writer->put(float_bits(x[t]), 32);
  return {BitBlocks::kRawWidth, 32ull * steps};
}

/// k_t of each step, or false where one falls outside [0, 2^first_width) or misses the bound.
bool predictive_integers(const float* x, std::uint32_t steps, const Quantiser& q, float bound, std::int64_t* k) {
  for (std::uint32_t t = 0; t < steps; ++t) {
    const double kd = round_to_integer((double(x[t]) - q.lo) / q.step);
    const float rebuilt = q.lo + float(kd) * q.step;
    if (!(kd >= 0 && kd < double(1ull << q.first_width)) || std::fabs(double(x[t]) - double(rebuilt)) > bound)
      return false;
    k[t] = std::int64_t(kd);
  }
  return true;
}

/// z[t - 1] = zigzag of k_t's prediction error under `predictor`, t = 1 .. steps-1; false (z
/// left partly written) where an error does not fit in 21 bits.
bool prediction_errors(const std::int64_t* k, std::uint32_t steps, std::uint32_t predictor, std::uint32_t* z) {
  for (std::uint32_t t = 1; t < steps; ++t) {
    const std::int64_t d = k[t] - predict(predictor, t, k[t - 1], t >= 2 ? k[t - 2] : 0);
    if (!(d < (1 << 20) && d > -(1 << 20))) return false;
    z[t - 1] = zigzag(std::int32_t(d));
  }
  return true;
}

}  // namespace

SectionCost encode_residual_section(const float* x, std::uint32_t steps, const float* base, float step, float bound,
                                    BitWriter* writer, std::uint32_t* z) {
  for (std::uint32_t t = 0; t < steps; ++t) {
    const double q = round_to_integer((double(x[t]) - base[t]) / step);
    if (!(std::fabs(q) < double(1 << 20))) return write_raw(x, steps, writer);
    const float rebuilt = base[t] + float(q) * step;
    if (std::fabs(double(x[t]) - double(rebuilt)) > bound) return write_raw(x, steps, writer);
    z[t] = zigzag(std::int32_t(q));
  }
  const ValueLayout layout = choose_layout(z, steps);
  if (layout.code == BitBlocks::kRawWidth) return write_raw(x, steps, writer);
  if (writer) write_values(*writer, z, steps, layout);
  return {layout.code, layout.bits};
}

SectionCost encode_predictive_section(const float* x, std::uint32_t steps, const Quantiser& q, float bound,
                                      BitWriter* writer, std::int64_t* k, std::uint32_t* z) {
  if (!predictive_integers(x, steps, q, bound, k)) return write_raw(x, steps, writer);
  const std::uint32_t count = steps - 1;
  ValueLayout best;
  best.code = BitBlocks::kRawWidth;
  best.bits = ~0ull;
  std::uint32_t best_predictor = 0;
  for (std::uint32_t predictor = 0; predictor < 2; ++predictor) {
    if (!prediction_errors(k, steps, predictor, z)) continue;
    const ValueLayout layout = choose_layout(z, count);
    if (layout.code != BitBlocks::kRawWidth && layout.bits < best.bits) best = layout, best_predictor = predictor;
  }
  if (best.code == BitBlocks::kRawWidth) return write_raw(x, steps, writer);
  if (writer) {
    prediction_errors(k, steps, best_predictor, z);
    writer->put(best_predictor, 1);
    writer->put(std::uint32_t(k[0]), q.first_width);
    write_values(*writer, z, count, best);
  }
  return {best.code, 1 + q.first_width + best.bits};
}

}  // namespace penumbra::compression::detail
