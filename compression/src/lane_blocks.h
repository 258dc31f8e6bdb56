// SPDX-License-Identifier: BSD-3-Clause
// compression/src/lane_blocks.h -- predictive_lanes pages: the predictive coder's integers in
// blocks of 16 vertices (private).
//
// Block b holds vertices 16 b .. 16 b + 15, one per lane; the last block's lanes past the page's
// vertices are padding (zero, never written out). Lane l's bits run down column l of `words`:
// word 16 r + l holds lane l's bits 32 r .. 32 r + 31, LSB first. A block starts at the same bit
// bit_start[b] of every column and holds there, in each lane, for a page of n steps:
//   k_0         first_width bits (the page's), k_0 itself
//   step 1      w1 bits: k_1 - k_0 in two's complement (width 0: the difference is 0)
//   step t >= 2 k_t - prediction_t in v bits, two's complement: v = w2 at step 2, w3 for the
//               transient steps 3 .. T - 1, w from the block's transient end T on; the
//               prediction is 2 k_{t-1} - k_{t-2} in `linear` lanes and k_{t-1} in the others
// Blocks follow each other without gaps (lane_block_bits gives a block's bits). A run's first
// steps often jump further than its later ones, and by how much and for how long differs from
// block to block, so steps 1 and 2 have widths of their own and each block chooses where its
// transient ends. A difference d too wide for its step's width is an exception: the block lists
// the step's row (step, lanes), and the high part h = (d - s) / 2^width, s being the slot's low
// bits as a signed value, zigzag-coded at the block's exception width x, follows in
// exception_bits. Raw lanes (values that lo + k step cannot hold within the bound) read 0 in
// every slot and take their n exact floats from raw_values. All integer arithmetic wraps in 32
// bits, so that the scalar and the vector decoders agree exactly.
// Older formats are read into this layout (page_format.cpp): version 4 had one width for steps
// 2 .. 5 and T = 6 for every block; version 3 one width for every step after step 1, and slots in
// offset binary (d + 2^(v-1)).
#pragma once
#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <string>

#include "bit_io.h"
#include "cpu_features.h"
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

/// A block's widths, in this order: step 1's, step 2's, the transient steps', the later steps',
/// the high parts'.
constexpr std::uint64_t kLaneWidths = 5;
inline std::uint32_t lane_width_1(const LaneBlocks& L, std::uint64_t b) { return L.widths[kLaneWidths * b]; }
inline std::uint32_t lane_width_2(const LaneBlocks& L, std::uint64_t b) { return L.widths[kLaneWidths * b + 1]; }
inline std::uint32_t lane_transient_width(const LaneBlocks& L, std::uint64_t b) { return L.widths[kLaneWidths * b + 2]; }
inline std::uint32_t lane_width(const LaneBlocks& L, std::uint64_t b) { return L.widths[kLaneWidths * b + 3]; }
inline std::uint32_t lane_exception_width(const LaneBlocks& L, std::uint64_t b) { return L.widths[kLaneWidths * b + 4]; }

/// A transient end is stored in a byte: a window of more steps ends its transient steps by then.
constexpr std::uint32_t kLaneMaxTransientEnd = 255;

/// Where format versions 3 and 4 ended every block's transient steps (or the window's end, if
/// sooner): version 4 gave steps 2 .. 5 one width.
constexpr std::uint32_t kOlderLaneTransientEnd = 6;

/// Where an n-step page's transient steps start: step 3, or n if it has fewer steps.
inline std::uint32_t lane_transient_start(std::uint32_t steps) { return std::min(steps, 3u); }

/// A run of a block's steps after step 1 that share one width: [from, to).
struct LaneStepSpan {
  std::uint32_t from, to, width;
};

/// Block b's steps after step 1 in an n-step page: step 2, the transient steps, the later ones.
inline std::array<LaneStepSpan, 3> lane_step_spans(const LaneBlocks& L, std::uint64_t b, std::uint32_t steps) {
  const std::uint32_t start = lane_transient_start(steps), end = L.transient_ends[b];
  return {{{std::min(steps, 2u), start, lane_width_2(L, b)}, {start, end, lane_transient_width(L, b)},
           {end, steps, lane_width(L, b)}}};
}

/// What is wrong with block b's widths and transient end for an n-step page (none over 32 bits,
/// the transient end in [min(n, 3), n], no width for a span without steps), or nullptr.
const char* lane_block_layout_error(const LaneBlocks& L, std::uint64_t b, std::uint32_t steps);

/// Bits block b (its layout valid) takes in each column.
inline std::uint64_t lane_block_bits(const LaneBlocks& L, std::uint64_t b, std::uint32_t first_width, std::uint32_t steps) {
  std::uint64_t bits = first_width + (steps >= 2 ? lane_width_1(L, b) : 0);
  for (const LaneStepSpan& s : lane_step_spans(L, b, steps)) bits += std::uint64_t(s.to - s.from) * s.width;
  return bits;
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

/// The row holding bit `end` of every column: (end / 32) rows of 64 bytes on from `rows`. Written
/// as end rounded down to 32, times 2 bytes, which GCC computes in an `and` and an `lea` where it
/// gave the row index two shifts and an add: with a 2-step unroll, 1.04-1.047x on mug's lane
/// pages (the step loop is bound by its instructions).
inline const std::uint32_t* row_holding(const std::uint32_t* rows, std::uint64_t end) {
  return reinterpret_cast<const std::uint32_t*>(reinterpret_cast<const char*>(rows) + (end & ~std::uint64_t(31)) * 2);
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
  if (t <= 2) return t == 1 ? lane_width_1(L, b) : lane_width_2(L, b);
  return t < L.transient_ends[b] ? lane_transient_width(L, b) : lane_width(L, b);
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

/// Asks for the line two blocks further along the row a block has just stored to. A block
/// writes one 64-byte piece of each of its steps' rows, rows 4 N bytes apart, too far apart for the
/// hardware's prefetchers to follow, so without this every store waited for its line (two, as most
/// rows do not start on a line) and the stores in flight bounded the kernel. 1.07-1.13x on mug's
/// lane pages held in cache, 1.2-1.5x on 100K vertices (rows in memory). A prefetch never faults:
/// the last blocks' ask past the range's rows, or past the window, is harmless.
inline void prefetch_row_ahead(const float* stored) { __builtin_prefetch(stored + 2 * kLaneBlock, 0, 3); }

/// The vector decoders lane blocks use: the widest the CPU has, unless set_vector_decode turned
/// the lanes off (scalar) or cap_lane_isa capped them (tests run each one this way). Always
/// scalar in a build without x86 kernels (cpu_features.h).
enum class LaneIsa { scalar = 0, avx2 = 1, avx512 = 2, avx512_vbmi2 = 3 };
LaneIsa lane_isa();
void cap_lane_isa(LaneIsa widest);

#if PNB_X86_KERNELS
/// The AVX2 window and cursor decoders (lane_blocks_avx2.cpp); raw lanes are left to the caller.
void lane_blocks_window_avx2(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window);
void lane_blocks_next_avx2(const EncodedPage& p, std::uint64_t b, std::uint64_t e, LaneBlockState* states, float* out);
#endif

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

/// How an encoder lays out a block's steps after step 1: as this format chooses them, or in a
/// layout an older format can hold (tests write such pages).
enum class LaneLayout {
  chosen,             ///< steps 2, 3 .. T - 1 and T .. n - 1 each at the width with the fewest bits, T per block
  transient_to_6,     ///< one width for steps 2 .. 5, one for the rest (format version 4)
  one_after_step_1,   ///< one width for every step after step 1 (format version 3)
};

/// Encodes a window of N vertices into lane blocks. gather(first, count, x) writes vertices
/// [first, first + count) to x, `window` floats each (the first `steps` meaningful). The
/// derived tables are left empty: lane_blocks_error derives them, as for a parsed page.
LaneBlocks build_lane_blocks(std::uint64_t N, std::uint32_t steps, std::uint32_t window, float lo, float step,
                             float bound, std::uint32_t first_width,
                             const std::function<void(std::uint64_t, std::uint64_t, float*)>& gather,
                             LaneLayout layout = LaneLayout::chosen);

/// Checks a predictive_lanes page's tables value by value (they must describe exactly the bits
/// and values stored, within their arrays) and derives bit_start, raw_start, row_start,
/// high_start and highs. With `derive`, writes them there; without, compares them with the
/// page's own. Returns an empty string or what is wrong.
std::string lane_blocks_error(const EncodedPage& p, LaneBlocks* derive);

}  // namespace penumbra::compression::detail
