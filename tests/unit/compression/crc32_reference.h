// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/crc32_reference.h -- CRC-32 (IEEE 802.3, bit-reflected 0xEDB88320) one
// bit at a time: obviously the definition, for checking the library's checksum and for editing
// files under test (rewriting a field and its checksum).
#pragma once
#include <cstddef>
#include <cstdint>

namespace penumbra::compression::testing {

/// CRC-32 of `size` bytes, continuing from `crc` (0 to start), as detail::crc32.
inline std::uint32_t crc32_reference(const void* data, std::size_t size, std::uint32_t crc = 0) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  crc = ~crc;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= p[i];
    for (int b = 0; b < 8; ++b) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

}  // namespace penumbra::compression::testing
