// SPDX-License-Identifier: BSD-3-Clause
// compression/src/step_cursor.cpp -- StepCursor: O(1) sequential steps of pages with bit blocks.
#include <string>

#include "cpu_features.h"
#include "cursor_state.h"
#include "page_methods.h"
#include "predictive_layout.h"
#include "section_lanes.h"
#include "step_base.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "vertex_section.h"
#include "vq_value.h"

namespace penumbra::compression {

namespace detail {

namespace {

// Bit position of the values of vertex v's section (after a predictive section's predictor
// bit and k_0).
std::uint64_t values_start(const EncodedPage& p, std::uint64_t v) {
  return p.blocks.section_start(v) + (p.method == PageMethod::predictive ? 1 + p.quantiser.first_width : 0);
}

}  // namespace

void seek(const EncodedPage& p, std::uint32_t i, CursorState& s) {
  const std::uint64_t N = p.vertex_count;
  const std::uint32_t count = value_count(p), pb = position_bits(count);
  s.slot.resize(N);
  s.width.resize(N);
  s.next.resize(N);
  s.entry.resize(N);
  s.left.resize(N);
  s.exception_width.resize(N);
  const bool predictive = p.method == PageMethod::predictive;
  s.linear.assign(predictive ? N : 0, 0);
  const std::uint8_t* data = p.blocks.payload.data();
  auto seek_vertex = [&](std::uint64_t v) {
    const std::uint32_t code = p.blocks.width(v);
    s.next[v] = CursorState::kNoException;
    s.slot[v] = s.entry[v] = 0;
    s.width[v] = s.left[v] = s.exception_width[v] = 0;
    if (code == BitBlocks::kRawWidth) return;
    if (predictive) s.linear[v] = std::uint8_t(read_bits(data, p.blocks.section_start(v), 1));
    const std::uint64_t group_bit = p.blocks.group_offsets[v / BitBlocks::kGroupSize] * 8;
    const ValueSpan span = parse_values(data, values_start(p, v), code, count);
    s.slot[v] = std::uint32_t(span.slots - group_bit);
    s.width[v] = std::uint8_t(span.width);
    s.exception_width[v] = std::uint8_t(span.exception_width);
    std::uint64_t at = span.exception_list;
    for (std::uint32_t x = 0; x < span.exceptions; ++x, at += pb + span.exception_width) {
      const std::uint32_t position = read_bits(data, at, pb);
      if (position >= i) {
        s.next[v] = std::uint16_t(position);
        s.entry[v] = std::uint32_t(at - group_bit);
        s.left[v] = std::uint8_t(span.exceptions - x);
        break;
      }
    }
  };
  // From the start of a page (sequential playback), the sections are parsed in lanes; a seek to
  // a later value index scans each vertex's exceptions, one vertex at a time.
  parallel_for(N, 1 << 14, [&](std::size_t b, std::size_t e) {
    std::uint64_t v = b;
#if PNB_X86_KERNELS
    if (i == 0 && lanes_active()) {
      v = b + (e - b) / kLanes * kLanes;
      // Lane blocks holding a raw section are left to the scalar seek.
      std::vector<std::uint64_t> raw_blocks((v - b) / kLanes);
      const std::uint64_t raw_block_count = seek_lanes(p, b, v, raw_blocks.data(), s);
      for (std::uint64_t k = 0; k < raw_block_count; ++k)
        for (std::uint64_t l = 0; l < kLanes; ++l) seek_vertex(raw_blocks[k] + l);
    }
#endif
    for (; v < e; ++v) seek_vertex(v);
  });
  s.raw.clear();
  for (std::uint64_t v = 0; v < N; ++v)
    if (p.blocks.width(v) == BitBlocks::kRawWidth) s.raw.push_back(v);
}

void cursor_step_vertex(const EncodedPage& p, std::uint32_t t, std::uint64_t v, float* out, CursorState& s) {
  const bool predictive = p.method == PageMethod::predictive;
  const std::uint32_t i = predictive ? t - 1 : t;
  const std::uint8_t* group = p.blocks.payload.data() + p.blocks.group_offsets[v / BitBlocks::kGroupSize];
  const std::uint32_t z = s.next[v] == i ? take_exception(p, v, s)
                                         : read_bits(group, s.slot[v] + std::uint64_t(i) * s.width[v], s.width[v]);
  if (predictive) {
    const std::int32_t k = next_k(s.linear[v], t, s.k1[v], s.k2[v], unzigzag(z));
    s.k2[v] = s.k1[v];
    s.k1[v] = k;
    out[v] = p.quantiser.lo + float(k) * p.quantiser.step;
  } else if (p.blocks.width(v) != 0) {
    // Code 0 (all zero) leaves the VQ value untouched, as decode_window does (keeps -0.0f).
    out[v] = out[v] + float(unzigzag(z)) * p.quantiser.step;
  }
}

}  // namespace detail

namespace {

// Vertices per parallel chunk of a cursor step (about 1 ns each): small enough that the chunks
// balance when a pager's background load takes a core for a while.
constexpr std::size_t kChunk = 1 << 13;

}  // namespace

StepCursor::StepCursor() = default;
StepCursor::~StepCursor() = default;
StepCursor::StepCursor(StepCursor&&) noexcept = default;
StepCursor& StepCursor::operator=(StepCursor&&) noexcept = default;

void StepCursor::decode(const std::shared_ptr<const EncodedPage>& page, std::uint32_t t, float* out) {
  require(page != nullptr, "StepCursor::decode: null page");
  const EncodedPage& p = *page;
  detail::require_decodable(p, "StepCursor::decode");
  if (!detail::has_bit_blocks(p.method) && p.method != PageMethod::predictive_lanes) {
    m_page.reset();
    m_state.reset();
    decode_step(p, t, out);
    return;
  }
  require(out != nullptr, "StepCursor::decode: null output");
  require(t < p.step_count, "StepCursor::decode: step " + std::to_string(t) + " is outside the page's " +
                                std::to_string(p.step_count) + " steps");
  const std::uint64_t N = p.vertex_count;
  const bool predictive = p.method == PageMethod::predictive;
  const bool follows = m_page == page && t == m_step + 1;
  m_step = t;
  if (p.method == PageMethod::predictive_lanes) {
    if (!m_state) m_state = std::make_unique<detail::CursorState>();
    std::vector<detail::LaneBlockState>& blocks = m_state->lane_blocks;
    const std::uint64_t B = detail::lane_block_count(N);
    if (!follows) {
      // Each block from its start to step t (O(t)); later steps then take one step each.
      m_page = page;
      blocks.resize(B);
      parallel_for(B, kChunk / detail::kLaneBlock, [&](std::size_t b, std::size_t e) {
        detail::lane_blocks_step(p, t, b, e, out, blocks.data() + b);
      });
      return;
    }
    parallel_for(B, kChunk / detail::kLaneBlock,
                 [&](std::size_t b, std::size_t e) { detail::lane_blocks_next(p, b, e, blocks.data(), out); });
    return;
  }
  if (!follows) {
    if (!m_state) m_state = std::make_unique<detail::CursorState>();
    detail::CursorState& s = *m_state;
    m_page = page;
    if (predictive) {
      s.k1.resize(N);
      s.k2.resize(N);
      detail::seek(p, t, s);  // the next step reads value index t
      // k_t needs the t prediction errors before it: one pass from each section's start.
      parallel_for(N, kChunk, [&](std::size_t b, std::size_t e) {
        detail::predictive_step_range(p, t, b, e, out, s.k1.data(), s.k2.data());
      });
      return;
    }
    // A residual value depends on nothing before it: point the cursor at step t and decode it
    // as a following step would be.
    detail::seek(p, t, s);
  }
  detail::CursorState& s = *m_state;
  parallel_for(N, kChunk, [&](std::size_t b, std::size_t e) {
    if (!predictive) detail::vq_base_step(p, t, b, e, out);
    std::uint64_t v = b;
#if PNB_X86_KERNELS
    if (detail::lanes_active()) {
      v = b + (e - b) / detail::kLanes * detail::kLanes;
      detail::cursor_step_lanes(p, t, b, v, out, s);
    }
#endif
    for (; v < e; ++v) detail::cursor_step_vertex(p, t, v, out, s);
  });
  const std::uint8_t* data = p.blocks.payload.data();
  for (const std::uint64_t v : s.raw) out[v] = detail::bits_float(detail::read_bits(data, p.blocks.section_start(v) + 32ull * t, 32));
}

}  // namespace penumbra::compression
