// SPDX-License-Identifier: BSD-3-Clause
// compression/src/value_layout.h -- how one vertex-window's integers are bit-packed (private).
//
// A vertex-window stores `count` unsigned (zigzag) integers z_i under a 4-bit code:
//   code 0..13   plain: count x code bits
//   code 14      patched: 4-bit width w, 4-bit exception count c (1..15), 5-bit exception
//                width ew, c exceptions of (position_bits index, ew-bit value), then
//                count x w bits (an exception's slot holds 0). One outlier, e.g. a jump in
//                time, then costs ~20 bits instead of widening every value; a window of
//                zeros with a few +-1 costs a few bits per nonzero.
//   code 15      raw: the vertex's float32 values (BitBlocks::kRawWidth), handled by callers
// Every value stays randomly accessible: a reader needs the header and the exception list.
#pragma once
#include <cstdint>

#include "bit_io.h"

namespace penumbra::compression::detail {

constexpr std::uint32_t kPatchedCode = 14;
constexpr std::uint32_t kMaxPlainWidth = 13;
constexpr std::uint32_t kMaxPatchedWidth = 15;
constexpr std::uint32_t kMaxExceptions = 15;
constexpr std::uint32_t kMaxExceptionWidth = 31;
constexpr std::uint32_t kPatchedHeaderBits = 13;

inline std::uint32_t position_bits(std::uint32_t count) { return count > 1 ? bit_width(count - 1) : 0; }

struct ValueLayout {
  std::uint32_t code = 0;    ///< 0..14, or 15 when the values cannot be packed
  std::uint32_t width = 0;   ///< bits per slot
  std::uint32_t exceptions = 0;
  std::uint32_t exception_width = 0;
  std::uint64_t bits = 0;    ///< total bits of the layout
};

/// The cheapest layout for z[0..count).
ValueLayout choose_layout(const std::uint32_t* z, std::uint32_t count);
void write_values(BitWriter& writer, const std::uint32_t* z, std::uint32_t count, const ValueLayout& layout);

/// A parsed vertex-window of values starting at bit `pos`.
struct ValueSpan {
  std::uint64_t exception_list = 0;  ///< bit position of the exception list
  std::uint64_t slots = 0;           ///< bit position of the first slot
  std::uint64_t end = 0;             ///< bit position after the values
  std::uint32_t width = 0, exceptions = 0, exception_width = 0;
};

/// Reads the header (if patched) at pos; `code` is the vertex's 4-bit code (< 15). Inline: the
/// decoders call it once per vertex-window, and a call returning the span through memory cost
/// them a store-forwarding stall per vertex.
inline ValueSpan parse_values(const std::uint8_t* data, std::uint64_t pos, std::uint32_t code, std::uint32_t count) {
  ValueSpan s;
  if (code != kPatchedCode) {
    s.width = code;
    s.slots = s.exception_list = pos;
  } else {
    s.width = read_bits(data, pos, 4);
    s.exceptions = read_bits(data, pos + 4, 4);
    s.exception_width = read_bits(data, pos + 8, 5);
    s.exception_list = pos + kPatchedHeaderBits;
    s.slots = s.exception_list + std::uint64_t(s.exceptions) * (position_bits(count) + s.exception_width);
  }
  s.end = s.slots + std::uint64_t(count) * s.width;
  return s;
}

/// Bits the header of a patched layout needs before its size is known (bounds checks).
inline std::uint64_t header_bits(std::uint32_t code) { return code == kPatchedCode ? kPatchedHeaderBits : 0; }

std::uint32_t value_at(const std::uint8_t* data, const ValueSpan& span, std::uint32_t count, std::uint32_t i);
void all_values(const std::uint8_t* data, const ValueSpan& span, std::uint32_t count, std::uint32_t* out);

}  // namespace penumbra::compression::detail
