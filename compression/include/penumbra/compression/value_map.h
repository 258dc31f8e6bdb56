// SPDX-License-Identifier: BSD-3-Clause
// compression/include/penumbra/compression/value_map.h
#pragma once
#include <cmath>
#include <cstdint>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::compression {

/// How a page's float32 values stand for the field's values: value = offset + scale x stored,
/// in double. A field whose values sit far from zero against their variation (an absolute
/// temperature, a pressure with its ambient part) or lie beyond float32's range (cgs energies,
/// SI quantities at the nanometre scale) keeps its variation in float32 this way. The offset and
/// the power-of-two scale are chosen per window, from its first step (format version 7); pages
/// of older files, and fields pushed as float32, have the identity map.
struct ValueMap {
  double offset = 0, scale = 1;

  bool identity() const { return offset == 0 && scale == 1; }
  /// The field value a stored value stands for.
  double value(float stored) const { return offset + scale * static_cast<double>(stored); }
  /// The stored value of a field value (infinite where it lies beyond float32 in this map). At
  /// the top of double's range, rounded toward zero where rounding to nearest would stand for a
  /// value beyond it.
  float stored(double value) const {
    const float x = static_cast<float>((value - offset) / scale);
    return std::isinf(this->value(x)) && std::isfinite(x) ? std::nextafter(x, 0.f) : x;
  }
  /// Whether the map is usable: offset finite, scale a positive, finite power of two.
  bool valid() const;
  bool operator==(const ValueMap&) const = default;

  /// The map for a window that starts with these values (the finite ones count): the offset is
  /// their midrange, the scale the power of two at their half-range (at the offset's magnitude
  /// for a constant step), so that the step stores in [-2, 2] with float32's relative precision
  /// of its range, whatever its magnitude or offset.
  static ValueMap fit(const double* values, std::uint64_t count);
};

/// out[i] = map.value(stored[i]) for i < count.
void apply_map(const ValueMap& map, const float* stored, std::uint64_t count, double* out);
/// values[i] = float(map.value(values[i])), in place: the field's values as float32, for readers
/// that take float32 (where the field lies beyond float32, or far from zero, this loses what
/// apply_map keeps).
void narrow_through_map(const ValueMap& map, float* values, std::uint64_t count);

}  // namespace penumbra::compression

PNB_PUBLIC_END
