// SPDX-License-Identifier: BSD-3-Clause
// compression/src/round_to_integer.h -- a quantiser's rounding without a library call (private).
#pragma once

namespace penumbra::compression::detail {

/// std::nearbyint(v) for |v| < 2^51, in the current rounding mode as nearbyint: adding and then
/// subtracting 1.5 * 2^52 leaves v rounded to an integer (a zero may come out with the other
/// sign). A larger |v| may round differently, so a caller must reject every result of 2^51 or
/// more in magnitude; the quantisers here hold at most 2^32 in a slot. The baseline x86-64
/// target has no rounding instruction, so std::nearbyint was a call into libm per value.
inline double round_to_integer(double v) {
  constexpr double kShift = 6755399441055744.0;  // 1.5 * 2^52
  return (v + kShift) - kShift;
}

}  // namespace penumbra::compression::detail
