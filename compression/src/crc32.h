// SPDX-License-Identifier: BSD-3-Clause
// compression/src/crc32.h -- CRC-32 (IEEE 802.3 polynomial), slice-by-8 (private).
#pragma once
#include <cstddef>
#include <cstdint>

namespace penumbra::compression::detail {

/// CRC-32 of `size` bytes, continuing from `crc` (0 to start).
std::uint32_t crc32(const void* data, std::size_t size, std::uint32_t crc = 0);

}  // namespace penumbra::compression::detail
