// SPDX-License-Identifier: BSD-3-Clause
// compression/src/value_layout.cpp
#include "value_layout.h"

#include <algorithm>
#include <array>

#include "penumbra/compression/encoded_page.h"

namespace penumbra::compression::detail {

ValueLayout choose_layout(const std::uint32_t* z, std::uint32_t count) {
  ValueLayout best;
  best.code = BitBlocks::kRawWidth;
  best.bits = ~0ull;
  // The kMaxExceptions + 1 widest values (widest first) decide every candidate.
  std::array<std::uint32_t, kMaxExceptions + 1> top{};
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::uint32_t w = bit_width(z[i]);
    if (w > top.back()) {
      std::uint32_t at = kMaxExceptions;
      while (at > 0 && top[at - 1] < w) {
        top[at] = top[at - 1];
        --at;
      }
      top[at] = w;
    }
  }
  if (top[0] <= kMaxPlainWidth) best = {top[0], top[0], 0, 0, std::uint64_t(count) * top[0]};
  if (top[0] > kMaxExceptionWidth) return best;
  const std::uint64_t pb = position_bits(count);
  for (std::uint32_t c = 1; c <= kMaxExceptions && c < count; ++c) {
    // Width top[c] leaves the values wider than it (at most c of them) as exceptions,
    // each stored with the widest exception's width.
    const std::uint32_t w = top[c];
    std::uint32_t wider = 0;
    for (std::uint32_t j = 0; j < c; ++j) wider += top[j] > w;
    if (w > kMaxPatchedWidth || wider == 0) continue;
    const std::uint32_t ew = top[0];
    const std::uint64_t bits = kPatchedHeaderBits + wider * (pb + ew) + std::uint64_t(count) * w;
    if (bits < best.bits) best = {kPatchedCode, w, wider, ew, bits};
    if (w == 0) break;  // no narrower width exists
  }
  return best;
}

void write_values(BitWriter& writer, const std::uint32_t* z, std::uint32_t count, const ValueLayout& layout) {
  if (layout.code != kPatchedCode) {
    for (std::uint32_t i = 0; i < count; ++i) writer.put(z[i], layout.width);
    return;
  }
  writer.put(layout.width, 4);
  writer.put(layout.exceptions, 4);
  writer.put(layout.exception_width, 5);
  const std::uint32_t pb = position_bits(count);
  const std::uint64_t limit = 1ull << layout.width;
  std::uint32_t written = 0;
  for (std::uint32_t i = 0; i < count && written < layout.exceptions; ++i)
    if (z[i] >= limit) {
      writer.put(i, pb);
      writer.put(z[i], layout.exception_width);
      ++written;
    }
  for (std::uint32_t i = 0; i < count; ++i) writer.put(z[i] >= limit ? 0 : z[i], layout.width);
}

std::uint32_t value_at(const std::uint8_t* data, const ValueSpan& s, std::uint32_t count, std::uint32_t i) {
  const std::uint32_t pb = position_bits(count);
  std::uint64_t at = s.exception_list;
  for (std::uint32_t e = 0; e < s.exceptions; ++e, at += pb + s.exception_width)
    if (read_bits(data, at, pb) == i) return read_bits(data, at + pb, s.exception_width);
  return read_bits(data, s.slots + std::uint64_t(i) * s.width, s.width);
}

void all_values(const std::uint8_t* data, const ValueSpan& s, std::uint32_t count, std::uint32_t* out) {
  std::uint64_t at = s.slots;
  for (std::uint32_t i = 0; i < count; ++i, at += s.width) out[i] = read_bits(data, at, s.width);
  const std::uint32_t pb = position_bits(count);
  at = s.exception_list;
  for (std::uint32_t e = 0; e < s.exceptions; ++e, at += pb + s.exception_width) {
    const std::uint32_t i = read_bits(data, at, pb);
    if (i < count) out[i] = read_bits(data, at + pb, s.exception_width);
  }
}

}  // namespace penumbra::compression::detail
