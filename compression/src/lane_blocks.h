// compression/src/lane_blocks.h -- predictive_lanes pages: the predictive coder's integers in
// blocks of 16 vertices (private).
//
// Block b holds vertices 16 b .. 16 b + 15, one per lane; the last block's lanes past the page's
// vertices are padding (zero, never written out). Lane l's bits run down column l of `words`:
// word 16 r + l holds lane l's bits 32 r .. 32 r + 31, LSB first. A block starts at the same bit
// bit_start[b] of every column and holds there, in each lane, for a page of n steps:
//   k_0         first_width bits (the page's), k_0 itself
//   step 1      w1 bits: k_1 - k_0 in two's complement (width 0: the difference is 0)
//   step t >= 2 k_t - prediction_t in v bits, two's complement: v = w2 for the transient steps
//               2 .. kLaneTransientEnd - 1, v = w after them; the prediction is
//               2 k_{t-1} - k_{t-2} in `linear` lanes and k_{t-1} in the others
// Blocks follow each other without gaps (lane_block_bits gives a block's bits). A run's first
// steps often jump further than its later ones, so step 1 and the transient steps have widths of
// their own. A difference d too wide for its step's width is an exception: the block lists the
// step's row (step, lanes), and the high part h = (d - s) / 2^width, s being the slot's low bits
// as a signed value, zigzag-coded at the block's exception width x, follows in exception_bits.
// Raw lanes (values that lo + k step cannot hold within the bound) read 0 in every slot and take
// their n exact floats from raw_values. All integer arithmetic wraps in 32 bits, so that the
// scalar and the vector decoders agree exactly.
// Format version 3 had no transient width, and its slots held d + 2^(v-1) (offset binary) with
// the same high parts: its pages are read with w2 = w and each slot's top bit flipped
// (page_format.cpp).
#pragma once
#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <string>

#include "bit_io.h"
#include "penumbra/compression/encoded_page.h"

namespace penumbra::compression::detail {

constexpr std::uint64_t kLaneBlock = LaneBlocks::kLanes;

inline std::uint64_t lane_block_count(std::uint64_t vertices) {
  return vertices / kLaneBlock + (vertices % kLaneBlock != 0);  // no wrap for any 64-bit count
}

/// Rows of words the file stores for `bits` bits per column. The scalar slot read loads its row
/// and the next, and a zero-width slot can sit at the very end (bit `bits`), so one spare row lies
/// past that row.
inline std::uint64_t lane_word_rows(std::uint64_t bits) { return bits / 32 + 2; }

/// Words a page holds in memory: a zero row before row 0, then the file's rows. The vector
/// decoders read the 32 bits that end at a slot's last bit, from the slot's row and the row
/// below it; for a slot in row 0 that is the zero row.
inline std::uint64_t lane_words_held(std::uint64_t bits) { return kLaneBlock * (1 + lane_word_rows(bits)); }

/// Row 0 of a page's columns.
inline const std::uint32_t* lane_rows(const LaneBlocks& L) { return L.words.data() + kLaneBlock; }

/// Lanes of block b that hold a vertex (16, fewer in the last block), and their bit mask.
inline std::uint64_t lane_block_lanes(std::uint64_t vertices, std::uint64_t b) {
  return std::min<std::uint64_t>(kLaneBlock, vertices - b * kLaneBlock);
}
inline std::uint16_t lane_block_mask(std::uint64_t vertices, std::uint64_t b) {
  const std::uint64_t lanes = lane_block_lanes(vertices, b);
  return std::uint16_t(lanes == kLaneBlock ? 0xFFFF : (1u << lanes) - 1);
}

/// The steps after step 1 that take the transient width w2: 2 .. kLaneTransientEnd - 1.
constexpr std::uint32_t kLaneTransientEnd = 6;

/// A block's widths, in this order: step 1's, the transient steps', the later steps', the high
/// parts'. Format version 3 stored three, without the transient one.
constexpr std::uint64_t kLaneWidths = 4;
inline std::uint32_t lane_width_1(const LaneBlocks& L, std::uint64_t b) { return L.widths[kLaneWidths * b]; }
inline std::uint32_t lane_width_2(const LaneBlocks& L, std::uint64_t b) { return L.widths[kLaneWidths * b + 1]; }
inline std::uint32_t lane_width(const LaneBlocks& L, std::uint64_t b) { return L.widths[kLaneWidths * b + 2]; }
inline std::uint32_t lane_exception_width(const LaneBlocks& L, std::uint64_t b) { return L.widths[kLaneWidths * b + 3]; }

/// Steps of an n-step page at the transient width, and after it.
inline std::uint32_t lane_transient_steps(std::uint32_t steps) {
  return std::min(steps, kLaneTransientEnd) - std::min(steps, 2u);
}
inline std::uint32_t lane_later_steps(std::uint32_t steps) { return steps - std::min(steps, kLaneTransientEnd); }

/// A run of a block's steps after step 1 that share one width: [from, to).
struct LaneStepSpan {
  std::uint32_t from, to, width;
};

/// Block b's steps after step 1 in an n-step page: the transient steps, then the later ones.
inline std::array<LaneStepSpan, 2> lane_step_spans(const LaneBlocks& L, std::uint64_t b, std::uint32_t steps) {
  const std::uint32_t transient_end = std::min(steps, kLaneTransientEnd);
  return {{{2, transient_end, lane_width_2(L, b)}, {transient_end, steps, lane_width(L, b)}}};
}

/// Bits a block takes in each column.
inline std::uint64_t lane_block_bits(std::uint32_t first_width, std::uint32_t w1, std::uint32_t w2, std::uint32_t w,
                                     std::uint32_t steps) {
  return first_width + (steps >= 2 ? w1 : 0) + std::uint64_t(lane_transient_steps(steps)) * w2 +
         std::uint64_t(lane_later_steps(steps)) * w;
}

inline std::uint32_t low_mask(std::uint32_t width) { return width >= 32 ? ~0u : (1u << width) - 1; }
/// The `width`-bit two's-complement value u (width 0: 0), in 32 bits.
inline std::uint32_t sign_extend(std::uint32_t u, std::uint32_t width) {
  return width ? std::uint32_t(std::int32_t(u << (32 - width)) >> (32 - width)) : 0u;
}

/// Lane l's `width` bits at bit `pos` of its column (`rows`: row 0; the spare row makes word
/// row + 1 readable).
inline std::uint32_t lane_slot(const std::uint32_t* rows, std::uint64_t pos, std::uint32_t lane, std::uint32_t width) {
  const std::uint64_t row = pos >> 5;
  const std::uint64_t pair = (std::uint64_t(rows[(row + 1) * kLaneBlock + lane]) << 32) | rows[row * kLaneBlock + lane];
  return std::uint32_t(pair >> (pos & 31)) & low_mask(width);
}

/// One block's decoder state: k at the last two steps of every lane, and where the block's
/// next step, exception row and high part are.
struct LaneBlockState {
  std::uint32_t k1[kLaneBlock], k2[kLaneBlock];
  std::uint32_t t = 0;
  std::uint64_t pos = 0;
  std::uint64_t row = 0, high = 0;
};

/// The width of block b's slots at step t >= 1.
inline std::uint32_t lane_step_width(const LaneBlocks& L, std::uint64_t b, std::uint32_t t) {
  return t == 1 ? lane_width_1(L, b) : t < kLaneTransientEnd ? lane_width_2(L, b) : lane_width(L, b);
}

/// True when block b's next exception row (from state s) is at the step s is about to decode.
inline bool exception_row_due(const LaneBlocks& L, std::uint64_t b, const LaneBlockState& s) {
  return s.row < L.row_start[b + 1] && L.exception_steps[s.row] == s.t;
}

/// The step of exception row `row` of a block whose rows end at `row_end`; 0 once none is left
/// (no exception lies at step 0).
inline std::uint32_t next_exception_step(const std::uint16_t* steps, std::uint64_t row, std::uint64_t row_end) {
  return row < row_end ? steps[row] : 0;
}

/// The vector decoders lane blocks use: the widest the CPU has, unless set_vector_decode turned
/// the lanes off (scalar) or cap_lane_isa capped them (tests run each one this way).
enum class LaneIsa { scalar = 0, avx2 = 1, avx512 = 2, avx512_vbmi2 = 3 };
LaneIsa lane_isa();
void cap_lane_isa(LaneIsa widest);

/// The AVX2 window and cursor decoders (lane_blocks_avx2.cpp); raw lanes are left to the caller.
void lane_blocks_window_avx2(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window);
void lane_blocks_next_avx2(const EncodedPage& p, std::uint64_t b, std::uint64_t e, LaneBlockState* states, float* out);

/// Points `s` at step 0 of block b.
void lane_block_begin(const EncodedPage& p, std::uint64_t b, LaneBlockState& s);

/// Decodes step s.t of block b into s.k1 (the step before moves to s.k2) and moves on.
void lane_block_step(const EncodedPage& p, std::uint64_t b, LaneBlockState& s);

/// Writes the current step (s.t - 1) of block b's vertices to row[v - 16 b], raw lanes included.
void lane_block_write(const EncodedPage& p, std::uint64_t b, const LaneBlockState& s, float* row);

/// decode_window for blocks [b, e) into window[t * vertex_count + v].
void lane_blocks_window(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window);

/// The next step of blocks [b, e) from their states (states[k] for block k), into out[v].
void lane_blocks_next(const EncodedPage& p, std::uint64_t b, std::uint64_t e, LaneBlockState* states, float* out);

/// Step t of blocks [b, e) from each block's start: O(t). Leaves each block's state after step
/// t in states[block - b] when given (a cursor starting at t).
void lane_blocks_step(const EncodedPage& p, std::uint32_t t, std::uint64_t b, std::uint64_t e, float* out,
                      LaneBlockState* states = nullptr);

/// Vertex v's whole window.
void lane_blocks_vertex(const EncodedPage& p, std::uint64_t v, float* out);

/// Encodes a window of N vertices into lane blocks. gather(first, count, x) writes vertices
/// [first, first + count) to x, `window` floats each (the first `steps` meaningful). The
/// derived tables are left empty: lane_blocks_error derives them, as for a parsed page. Without
/// `transient_width`, the transient steps take the later steps' width (w2 = w, the layout format
/// version 3 can hold).
LaneBlocks build_lane_blocks(std::uint64_t N, std::uint32_t steps, std::uint32_t window, float lo, float step,
                             float bound, std::uint32_t first_width,
                             const std::function<void(std::uint64_t, std::uint64_t, float*)>& gather,
                             bool transient_width = true);

/// Checks a predictive_lanes page's tables value by value (they must describe exactly the bits
/// and values stored, within their arrays) and derives bit_start, raw_start, row_start,
/// high_start and highs. With `derive`, writes them there; without, compares them with the
/// page's own. Returns an empty string or what is wrong.
std::string lane_blocks_error(const EncodedPage& p, LaneBlocks* derive);

}  // namespace penumbra::compression::detail
