// SPDX-License-Identifier: BSD-3-Clause
// compression/src/lane_blocks_checks.cpp -- a predictive_lanes page's tables checked value by
// value, and the block offsets derived from them.
#include <bit>
#include <cmath>

#include "lane_blocks.h"

namespace penumbra::compression::detail {

namespace {

std::string at_block(const char* what, std::uint64_t b) { return std::string(what) + " at lane block " + std::to_string(b); }

}  // namespace

const char* lane_block_layout_error(const LaneBlocks& L, std::uint64_t b, std::uint32_t steps) {
  for (std::uint64_t i = 0; i < kLaneWidths; ++i)
    if (L.widths[kLaneWidths * b + i] > 32) return "width over 32 bits";
  const std::uint32_t end = L.transient_ends[b];
  if (end < lane_transient_start(steps) || end > steps) return "transient end outside the window's steps";
  if (steps < 2 && lane_width_1(L, b) != 0) return "width for a step the page does not have";
  for (const LaneStepSpan& s : lane_step_spans(L, b, steps))
    if (s.from == s.to && s.width != 0) return "width for a step the page does not have";
  return nullptr;
}

std::string lane_blocks_error(const EncodedPage& p, LaneBlocks* derive) {
  const LaneBlocks& L = p.lanes;
  const std::uint64_t N = p.vertex_count, B = lane_block_count(N);
  const std::uint32_t n = p.step_count;
  if (p.quantiser.first_width < 1 || p.quantiser.first_width > 31) return "first-value width " + std::to_string(p.quantiser.first_width) + " outside 1..31";
  if (!std::isfinite(p.quantiser.step) || !std::isfinite(p.quantiser.lo)) return "non-finite quantisation step";
  if (L.widths.size() != kLaneWidths * B || L.transient_ends.size() != B || L.linear.size() != B || L.raw.size() != B ||
      L.exception_rows.size() != B)
    return "lane block tables do not have one entry per block of 16 vertices";
  LaneBlocks d;
  d.bit_start.resize(B + 1);
  d.raw_start.resize(B + 1);
  d.row_start.resize(B + 1);
  d.high_start.resize(B + 1);
  std::uint64_t bits = 0, raw = 0, rows = 0, highs = 0, high_bits = 0;
  for (std::uint64_t b = 0; b < B; ++b) {
    d.bit_start[b] = bits;
    d.raw_start[b] = raw;
    d.row_start[b] = rows;
    d.high_start[b] = highs;
    if (const char* error = lane_block_layout_error(L, b, n)) return at_block(error, b);
    const std::uint32_t x = lane_exception_width(L, b);
    // Lanes past the last vertex are padding: nothing may be stored for them.
    const std::uint16_t mask = lane_block_mask(N, b);
    if ((L.linear[b] & ~mask) || (L.raw[b] & ~mask)) return at_block("predictor or raw flag on a padding lane", b);
    bits += lane_block_bits(L, b, p.quantiser.first_width, n);
    raw += std::uint64_t(std::popcount(L.raw[b])) * n;
    const std::uint64_t row_end = rows + L.exception_rows[b];
    if (row_end > L.exception_steps.size() || row_end > L.exception_lanes.size())
      return at_block("exception rows past the row table", b);
    std::uint32_t previous = 0;
    for (std::uint64_t r = rows; r < row_end; ++r) {
      const std::uint32_t t = L.exception_steps[r], lanes = L.exception_lanes[r];
      if (t <= previous || t >= n) return at_block("exception steps not increasing inside the window", b);
      if (lanes == 0 || (lanes & ~mask)) return at_block("exception row with no lanes, or a padding lane", b);
      previous = t;
      highs += std::uint64_t(std::popcount(lanes));
      high_bits += std::uint64_t(std::popcount(lanes)) * x;
    }
    rows = row_end;
  }
  d.bit_start[B] = bits;
  d.raw_start[B] = raw;
  d.row_start[B] = rows;
  d.high_start[B] = highs;
  if (L.exception_steps.size() != rows || L.exception_lanes.size() != rows) return "exception row tables have the wrong size";
  if (L.exception_bits.size() != (high_bits + 7) / 8 + 8) return "exception high parts have the wrong size";
  if (L.raw_values.size() != raw) return "raw lane values have the wrong size";
  if (L.words.size() != lane_words_held(bits)) return "lane words have the wrong size";
  // The high parts, unpacked and signed, in row order.
  d.highs.resize(highs);
  std::uint64_t at = 0;
  for (std::uint64_t b = 0; b < B; ++b) {
    const std::uint32_t x = lane_exception_width(L, b);
    for (std::uint64_t h = d.high_start[b]; h < d.high_start[b + 1]; ++h, at += x)
      d.highs[h] = std::uint32_t(unzigzag(read_bits(L.exception_bits.data(), at, x)));
  }
  if (derive) {
    derive->bit_start = std::move(d.bit_start);
    derive->raw_start = std::move(d.raw_start);
    derive->row_start = std::move(d.row_start);
    derive->high_start = std::move(d.high_start);
    derive->highs = std::move(d.highs);
    return {};
  }
  if (d.bit_start != L.bit_start || d.raw_start != L.raw_start || d.row_start != L.row_start ||
      d.high_start != L.high_start || d.highs != L.highs)
    return "derived lane block offsets do not match the tables";
  return {};
}

}  // namespace penumbra::compression::detail
