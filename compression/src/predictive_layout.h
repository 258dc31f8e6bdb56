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

inline std::uint64_t predictive_vertex_bits(std::uint32_t first_width, std::uint32_t steps, std::uint32_t width) {
  return 1 + first_width + std::uint64_t(steps - 1) * width;
}

}  // namespace penumbra::compression::detail
