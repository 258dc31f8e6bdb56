// SPDX-License-Identifier: BSD-3-Clause
// compression/src/crc32.cpp
#include "crc32.h"

#include <array>
#include <cstring>

#include "cpu_features.h"
#if PNB_X86_KERNELS
#include <immintrin.h>
#endif

namespace penumbra::compression::detail {

namespace {

using Tables = std::array<std::array<std::uint32_t, 256>, 8>;

Tables make_tables() {
  Tables t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[0][i] = c;
  }
  for (std::uint32_t i = 0; i < 256; ++i)
    for (int s = 1; s < 8; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFF];
  return t;
}

const Tables& tables() {
  static const Tables t = make_tables();
  return t;
}

#if PNB_X86_KERNELS
#define PNB_CLMUL __attribute__((target("pclmul,sse4.1"), always_inline)) inline

PNB_CLMUL __m128i load(const std::uint8_t* at) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(at)); }

// x folded 128 bits (k's distances) onward and added to the next block.
PNB_CLMUL __m128i fold(__m128i x, __m128i k, __m128i next) {
  return _mm_xor_si128(_mm_xor_si128(_mm_clmulepi64_si128(x, k, 0x00), _mm_clmulepi64_si128(x, k, 0x11)), next);
}

// Folds 16-byte blocks with carry-less multiplies (PCLMULQDQ): four 128-bit lanes 64 bytes
// apart, folded into one, then a 64- and a 32-bit fold and a Barrett reduction to the 32-bit
// remainder (the standard method for the bit-reflected polynomial). `reg` is the CRC register
// (not inverted); `size` is a multiple of 16 and at least 64. Several times the table's speed:
// a page load's checksum no longer takes most of its time.
__attribute__((target("pclmul,sse4.1"))) std::uint32_t fold_pclmul(const std::uint8_t* p, std::size_t size,
                                                                   std::uint32_t reg) {
  // x^(k) mod P for the fold distances (bit-reflected, shifted by one).
  const __m128i k1k2 = _mm_set_epi64x(0x1c6e41596, 0x154442bd4);  // 512 +/- 64 bits
  const __m128i k3k4 = _mm_set_epi64x(0x0ccaa009e, 0x1751997d0);  // 128 +/- 64 bits
  const __m128i k5 = _mm_set_epi64x(0, 0x163cd6124);              // 64 bits
  const __m128i poly = _mm_set_epi64x(0x1f7011641, 0x1db710641);  // Barrett mu, P
  const __m128i mask32 = _mm_set_epi32(0, 0, 0, -1);
  __m128i x1 = _mm_xor_si128(load(p), _mm_cvtsi32_si128(static_cast<int>(reg)));
  __m128i x2 = load(p + 16), x3 = load(p + 32), x4 = load(p + 48);
  p += 64;
  size -= 64;
  for (; size >= 64; size -= 64, p += 64) {
    x1 = fold(x1, k1k2, load(p));
    x2 = fold(x2, k1k2, load(p + 16));
    x3 = fold(x3, k1k2, load(p + 32));
    x4 = fold(x4, k1k2, load(p + 48));
  }
  x1 = fold(x1, k3k4, x2);
  x1 = fold(x1, k3k4, x3);
  x1 = fold(x1, k3k4, x4);
  for (; size >= 16; size -= 16, p += 16) x1 = fold(x1, k3k4, load(p));
  // 128 -> 64 bits, then 64 -> 32 (each appends zeros to the message).
  x1 = _mm_xor_si128(_mm_srli_si128(x1, 8), _mm_clmulepi64_si128(x1, k3k4, 0x10));
  x1 = _mm_xor_si128(_mm_srli_si128(x1, 4), _mm_clmulepi64_si128(_mm_and_si128(x1, mask32), k5, 0x00));
  // Barrett reduction to the remainder.
  __m128i t = _mm_clmulepi64_si128(_mm_and_si128(x1, mask32), poly, 0x10);
  t = _mm_clmulepi64_si128(_mm_and_si128(t, mask32), poly, 0x00);
  return static_cast<std::uint32_t>(_mm_extract_epi32(_mm_xor_si128(x1, t), 1));
}
#endif  // PNB_X86_KERNELS

}  // namespace

std::uint32_t crc32(const void* data, std::size_t size, std::uint32_t crc) {
  const Tables& t = tables();
  const auto* p = static_cast<const std::uint8_t*>(data);
  crc = ~crc;
#if PNB_X86_KERNELS
  static const bool has_pclmul = cpu_features().pclmul && cpu_features().sse41;
  if (has_pclmul && size >= 64) {
    const std::size_t blocks = size / 16 * 16;
    crc = fold_pclmul(p, blocks, crc);
    p += blocks;
    size -= blocks;
  }
#endif
  while (size >= 8) {
    std::uint32_t lo, hi;
    std::memcpy(&lo, p, 4);
    std::memcpy(&hi, p + 4, 4);
    lo ^= crc;
    crc = t[7][lo & 0xFF] ^ t[6][(lo >> 8) & 0xFF] ^ t[5][(lo >> 16) & 0xFF] ^ t[4][lo >> 24] ^ t[3][hi & 0xFF] ^
          t[2][(hi >> 8) & 0xFF] ^ t[1][(hi >> 16) & 0xFF] ^ t[0][hi >> 24];
    p += 8;
    size -= 8;
  }
  while (size--) crc = t[0][(crc ^ *p++) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

}  // namespace penumbra::compression::detail
