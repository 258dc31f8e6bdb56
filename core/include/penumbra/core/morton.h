// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/morton.h -- Morton (Z-order) codes, for cache-friendly orders
#pragma once
#include <cstdint>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra {

/// The low 21 bits of x spread to every third bit: interleaving three of these (shifted by 0, 1
/// and 2) gives a 63-bit Morton code.
inline std::uint64_t spread_bits_3d(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

}  // namespace penumbra

PNB_PUBLIC_END
