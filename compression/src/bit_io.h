// SPDX-License-Identifier: BSD-3-Clause
// compression/src/bit_io.h -- LSB-first bit packing for BitBlocks payloads (private).
#pragma once
#include <bit>
#include <cstdint>
#include <cstring>
#include <vector>

namespace penumbra::compression::detail {

/// Appends values of a given width (<= 32 bits) to a byte vector, LSB first.
class BitWriter {
public:
  explicit BitWriter(std::vector<std::uint8_t>& out) : m_out(out) {}
  void put(std::uint32_t value, unsigned width) {
    if (width == 0) return;
    m_acc |= std::uint64_t(value & mask(width)) << m_bits;
    m_bits += width;
    while (m_bits >= 8) {
      m_out.push_back(std::uint8_t(m_acc));
      m_acc >>= 8;
      m_bits -= 8;
    }
  }
  /// Pads the last byte; the next value starts byte-aligned.
  void flush() {
    if (m_bits) m_out.push_back(std::uint8_t(m_acc));
    m_acc = 0;
    m_bits = 0;
  }
  std::uint64_t bit_count() const { return m_out.size() * 8 + m_bits; }

private:
  static std::uint64_t mask(unsigned width) { return width >= 64 ? ~0ull : (1ull << width) - 1; }
  std::vector<std::uint8_t>& m_out;
  std::uint64_t m_acc = 0;
  unsigned m_bits = 0;
};

/// Reads `width` (<= 32) bits at bit position `pos`; the buffer has 8 bytes of padding.
inline std::uint32_t read_bits(const std::uint8_t* data, std::uint64_t pos, unsigned width) {
  if (width == 0) return 0;
  std::uint64_t word;
  std::memcpy(&word, data + (pos >> 3), 8);
  return std::uint32_t((word >> (pos & 7)) & ((1ull << width) - 1));
}

/// read_bits without the width-0 shortcut (branch-free in a loop): reads the 8 bytes at
/// pos / 8 even for width 0, so pos must lie within the payload or its padding.
inline std::uint32_t read_bits_branchless(const std::uint8_t* data, std::uint64_t pos, unsigned width) {
  std::uint64_t word;
  std::memcpy(&word, data + (pos >> 3), 8);
  return std::uint32_t((word >> (pos & 7)) & ((1ull << width) - 1));
}

inline std::uint32_t zigzag(std::int32_t v) { return (std::uint32_t(v) << 1) ^ std::uint32_t(v >> 31); }
inline std::int32_t unzigzag(std::uint32_t u) { return std::int32_t(u >> 1) ^ -std::int32_t(u & 1); }

inline unsigned bit_width(std::uint32_t v) { return static_cast<unsigned>(std::bit_width(v)); }

inline std::uint32_t float_bits(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}
inline float bits_float(std::uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

}  // namespace penumbra::compression::detail
