// SPDX-License-Identifier: BSD-3-Clause
// compression/src/cursor_state.h -- what a StepCursor keeps per vertex between steps (private).
//
// Sequential playback of a page with bit blocks (residual or predictive) reads value index i
// of every vertex at each step (residual: i = t; predictive: i = t - 1, its values being the
// prediction errors of steps 1..n-1). A patched section's value i is an exception or its slot;
// the exceptions lie in increasing position order, so the cursor keeps, per vertex, where its
// slots start, their width, and the position of its next exception. A step then costs one slot
// read per vertex and, rarely, one exception read: O(1), with no scan of the exception list
// and no per-step header parse. Raw sections (exact floats) are listed and read directly.
#pragma once
#include <cstdint>
#include <vector>

#include "bit_io.h"
#include "cpu_features.h"
#include "lane_blocks.h"
#include "penumbra/compression/encoded_page.h"
#include "value_layout.h"

namespace penumbra::compression::detail {

struct CursorState {
  static constexpr std::uint16_t kNoException = 0xFFFF;  // windows hold at most 1024 steps
  std::vector<std::uint32_t> slot;   ///< bit offset of slot 0 from the vertex's group start (raw: 0)
  std::vector<std::uint8_t> width;   ///< slot width in bits (raw: 0)
  std::vector<std::uint16_t> next;   ///< value index of the next exception not yet read
  std::vector<std::uint32_t> entry;  ///< bit offset of that exception's entry from the group start
  std::vector<std::uint8_t> left;    ///< exceptions not yet read, that one included
  std::vector<std::uint8_t> exception_width;
  std::vector<std::int32_t> k1, k2;  ///< predictive: k at the last step and the one before
  std::vector<std::uint8_t> linear;  ///< predictive: 1 where the vertex's predictor extrapolates
  std::vector<std::uint64_t> raw;    ///< vertices stored as exact floats, increasing
  std::vector<LaneBlockState> lane_blocks;  ///< predictive_lanes: each block's state after the last step
};

/// Values per vertex section: the page's steps, or one fewer for a predictive page.
inline std::uint32_t value_count(const EncodedPage& p) {
  return p.method == PageMethod::predictive ? p.step_count - 1 : p.step_count;
}

/// Points every vertex at value index i (the next one the cursor reads): slots, widths, and
/// the first exception at or after i.
void seek(const EncodedPage& p, std::uint32_t i, CursorState& s);

#if PNB_X86_KERNELS
/// seek(p, 0, s) for the lane blocks of [b, e) (whole blocks, section_lanes.cpp): the sections
/// parsed side by side. Blocks with a raw lane are left out: their first vertices are written to
/// `left_out` (room for (e - b) / 8 entries) and their count is returned, for the scalar seek.
std::uint64_t seek_lanes(const EncodedPage& p, std::uint64_t b, std::uint64_t e, std::uint64_t* left_out,
                         CursorState& s);
#endif

/// Vertex v's exception at value index s.next[v], moving its next exception on. Inline: the
/// lanes call it for every exception they meet.
inline std::uint32_t take_exception(const EncodedPage& p, std::uint64_t v, CursorState& s) {
  const std::uint8_t* group = p.blocks.payload.data() + p.blocks.group_offsets[v / BitBlocks::kGroupSize];
  const std::uint32_t pb = position_bits(value_count(p)), step = pb + s.exception_width[v];
  const std::uint32_t z = read_bits(group, s.entry[v] + pb, s.exception_width[v]);
  if (--s.left[v] == 0) {
    s.next[v] = CursorState::kNoException;
  } else {
    s.entry[v] += step;
    s.next[v] = std::uint16_t(read_bits(group, s.entry[v], pb));
  }
  return z;
}

/// Step t of a predictive page for vertices [b, e) from the start of each section: O(t).
/// Writes k_t and k_{t-1} into k1, k2 when given (a cursor starting at t).
void predictive_step_range(const EncodedPage& p, std::uint32_t t, std::uint64_t b, std::uint64_t e, float* out,
                           std::int32_t* k1 = nullptr, std::int32_t* k2 = nullptr);

/// The scalar cursor step for vertex v at step t (i its value index); `out` holds the VQ value
/// on residual pages. Raw vertices are left to the caller.
void cursor_step_vertex(const EncodedPage& p, std::uint32_t t, std::uint64_t v, float* out, CursorState& s);

#if PNB_X86_KERNELS
/// The same for the lane blocks of [b, e) (section_lanes.cpp).
void cursor_step_lanes(const EncodedPage& p, std::uint32_t t, std::uint64_t b, std::uint64_t e, float* out,
                       CursorState& s);
#endif

}  // namespace penumbra::compression::detail
