// SPDX-License-Identifier: BSD-3-Clause
// compression/src/predictive_layout.h -- bit layout of one predictive vertex-window (private).
//
// A vertex-window of the predictive coder holds integers k_t (value = lo + k_t * step):
//   1 bit   predictor: 0 = previous value, 1 = linear extrapolation 2 k_{t-1} - k_{t-2}
//   k_0     first_width bits
//   d_t     zigzag(k_t - prediction_t), t = 1..n-1, `width` bits each (step 1 always uses
//           the previous value: there is only one value before it)
// Integer prediction keeps encoder and decoder exactly in step.
#pragma once
#include <cstdint>

namespace penumbra::compression::detail {

inline std::int64_t predict(std::uint32_t predictor, std::uint32_t t, std::int64_t k1, std::int64_t k2) {
  return predictor == 1 && t >= 2 ? 2 * k1 - k2 : k1;
}

/// The decoder's k_t from k_{t-1}, k_{t-2} and the prediction error `delta`, in wrapping 32-bit
/// arithmetic: every valid k lies in [0, 2^31), so the wrapped sum is exact, and vector lanes
/// (section_lanes.h) compute the very same integers.
inline std::int32_t next_k(std::uint32_t predictor, std::uint32_t t, std::int32_t k1, std::int32_t k2,
                           std::int32_t delta) {
  const std::uint32_t prediction =
      predictor == 1 && t >= 2 ? 2u * std::uint32_t(k1) - std::uint32_t(k2) : std::uint32_t(k1);
  return std::int32_t(prediction + std::uint32_t(delta));
}

inline std::uint64_t predictive_vertex_bits(std::uint32_t first_width, std::uint32_t steps, std::uint32_t width) {
  return 1 + first_width + std::uint64_t(steps - 1) * width;
}

}  // namespace penumbra::compression::detail
