// SPDX-License-Identifier: BSD-3-Clause
// compression/src/value_map.cpp -- a window's double offset and power-of-two scale
#include "penumbra/compression/value_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace penumbra::compression {

bool ValueMap::valid() const {
  int exponent = 0;
  return std::isfinite(offset) && std::isfinite(scale) && scale > 0 && std::frexp(scale, &exponent) == 0.5;
}

ValueMap ValueMap::fit(const double* values, std::uint64_t count) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::uint64_t i = 0; i < count; ++i)
    if (std::isfinite(values[i])) lo = std::min(lo, values[i]), hi = std::max(hi, values[i]);
  if (!(lo <= hi)) return {};
  // Halves first: hi - lo overflows for values of opposite sign near DBL_MAX.
  const double half = hi / 2 - lo / 2;
  ValueMap map;
  map.offset = lo + half;
  const double magnitude = half > 0 ? half : std::fabs(map.offset);
  // ldexp(1, ilogb(m)) is the power of two at or below m: the step stores within [-2, 2].
  map.scale = magnitude > 0 ? std::ldexp(1.0, std::ilogb(magnitude)) : 1.0;
  return map;
}

void apply_map(const ValueMap& map, const float* stored, std::uint64_t count, double* out) {
  for (std::uint64_t i = 0; i < count; ++i) out[i] = map.value(stored[i]);
}

void narrow_through_map(const ValueMap& map, float* values, std::uint64_t count) {
  if (map.identity()) return;
  for (std::uint64_t i = 0; i < count; ++i) values[i] = static_cast<float>(map.value(values[i]));
}

}  // namespace penumbra::compression
