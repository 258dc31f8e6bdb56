// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/crc32_test.cpp -- the page checksum against the bit-by-bit CRC-32, on every
// length around the carry-less-multiply path's block sizes and from any starting value.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "crc32.h"
#include "crc32_reference.h"

namespace penumbra::compression {
namespace {

TEST(Crc32, MatchesTheStandardCheckValue) {
  const char* check = "123456789";
  EXPECT_EQ(detail::crc32(check, 9), 0xCBF43926u);
}

TEST(Crc32, MatchesABitwiseCrcOnEveryLengthAndStart) {
  std::mt19937 rng(7);
  std::vector<std::uint8_t> buf(5000);
  for (auto& b : buf) b = static_cast<std::uint8_t>(rng());
  std::vector<std::size_t> lengths;
  for (std::size_t n = 0; n <= 300; ++n) lengths.push_back(n);
  for (std::size_t n : {1023u, 1024u, 1025u, 4096u, 4999u, 5000u}) lengths.push_back(n);
  for (std::size_t n : lengths)
    for (std::size_t offset : {0u, 1u, 7u}) {
      if (offset + n > buf.size()) continue;
      const std::uint32_t start = rng();
      ASSERT_EQ(detail::crc32(buf.data() + offset, n, start), testing::crc32_reference(buf.data() + offset, n, start))
          << "length " << n << " offset " << offset;
    }
  // Continuing a checksum over two parts equals one pass.
  const std::uint32_t whole = detail::crc32(buf.data(), 3000);
  EXPECT_EQ(detail::crc32(buf.data() + 1234, 3000 - 1234, detail::crc32(buf.data(), 1234)), whole);
}

}  // namespace
}  // namespace penumbra::compression
