// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/checksum.h -- the checksum of the store's own files
#pragma once
#include <cstddef>
#include <cstdint>

namespace penumbra::insitu {

/// FNV-1a, 64 bit, continuing from `h`: catches truncation and bit rot; not a security measure.
inline std::uint64_t fnv1a(const unsigned char* p, std::size_t n, std::uint64_t h = 1469598103934665603ull) {
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

}  // namespace penumbra::insitu
