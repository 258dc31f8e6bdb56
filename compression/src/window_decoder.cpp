// SPDX-License-Identifier: BSD-3-Clause
// compression/src/window_decoder.cpp -- decodes a page: one step, the whole window, or one vertex.
#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "bit_io.h"
#include "cpu_features.h"
#include "cursor_state.h"
#include "lane_blocks.h"
#include "page_checks.h"
#include "page_methods.h"
#include "predictive_layout.h"
#include "section_lanes.h"
#include "step_base.h"
#include "vertex_section.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "vq_lanes.h"
#include "vq_value.h"

namespace penumbra::compression {

namespace {

constexpr std::uint64_t kGroup = BitBlocks::kGroupSize;
// Vertices per parallel chunk of a one-step decode: below a few hundred thousand vertices
// starting threads costs more than the decode (about 1 ns per vertex) itself.
constexpr std::size_t kStepChunk = 1 << 18;
// A page with a residual is decoded in runs of this many vertices. An aligned page's run is its
// VQ base then its residual, so that the residual pass adds to rows still in L2 (128 KB for 64
// steps): over a whole parallel chunk (8192 vertices, 2 MB) it read them back from L3 (on plain
// pages, then decoded the same way: eeg at 1e-3 8.6 -> 9.9 GB/s, smooth at 1e-2 21.8 -> 23.0,
// 100K vertices x 128 steps, medians of four alternated runs). A plain page's run is one
// residual chunk (vq_residual_lanes).
constexpr std::uint64_t kResidualRun = detail::kResidualChunk;

bool is_vq(const EncodedPage& p) { return detail::uses_plain_vq(p.method); }
bool is_aligned(const EncodedPage& p) { return detail::uses_aligned_vq(p.method); }
bool has_residual(const EncodedPage& p) {
  return p.method == PageMethod::vq_residual || p.method == PageMethod::vq_aligned_residual;
}

constexpr std::uint64_t kNoLimit = ~0ull;

// Zigzag value `i` of a patched span at bit `pos` (value_layout.h), inlined for the one-step
// loop: the exception list is in increasing position order (checked when a page is parsed),
// so the scan stops at the first position >= i; most steps read one slot.
inline std::uint32_t patched_value(const std::uint8_t* data, std::uint64_t pos, std::uint32_t pb, std::uint32_t i) {
  const std::uint32_t h = detail::read_bits(data, pos, detail::kPatchedHeaderBits);
  const std::uint32_t w = h & 0xF, c = (h >> 4) & 0xF, ew = h >> 8;
  const std::uint32_t entry = pb + ew;
  std::uint64_t at = pos + detail::kPatchedHeaderBits;
  for (std::uint32_t e = 0; e < c; ++e, at += entry) {
    std::uint64_t word;
    std::memcpy(&word, data + (at >> 3), 8);
    word >>= at & 7;  // >= 57 valid bits; an entry has at most 10 + 31
    const std::uint32_t position = std::uint32_t(word & ((1ull << pb) - 1));
    if (position == i) return std::uint32_t((word >> pb) & ((1ull << ew) - 1));
    if (position > i) break;
  }
  const std::uint64_t slots = pos + detail::kPatchedHeaderBits + std::uint64_t(c) * entry;
  return detail::read_bits(data, slots + std::uint64_t(i) * w, w);
}

// Adds the residual of step t to the VQ base of vertices [b, e) of a page with a residual:
// one read at a known offset and width per vertex (section offsets), no walk over a group.
// Plain sections (codes 0..13) go branch-free in a first pass; patched and raw ones, whose
// codes would mispredict a branch per vertex, are listed and done in a second.
void residual_step_range(const EncodedPage& p, std::uint32_t t, std::uint64_t b, std::uint64_t e, float* out) {
  const std::uint8_t* data = p.blocks.payload.data();
  const std::uint32_t pb = detail::position_bits(p.step_count);
  const float step = p.quantiser.step;
  thread_local std::vector<std::uint64_t> special;
  special.clear();
  const std::uint8_t* widths = p.blocks.widths.data();
  std::uint64_t v = b;
#if PNB_X86_KERNELS
  if (detail::lanes_active()) {
    v = b + (e - b) / detail::kLanes * detail::kLanes;
    detail::residual_step_lanes(p, t, b, v, out, special);
  }
#endif
  for (; v < e; ++v) {
    if ((v & 15) == 0 && v + 16 <= e) {
      // Sparse residuals (most codes 0) skip 16 vertices per 8-byte load of their codes.
      std::uint64_t codes;
      std::memcpy(&codes, widths + v / 2, 8);
      if (codes == 0) {
        v += 15;
        continue;
      }
    }
    const std::uint32_t code = p.blocks.width(v);
    if (code >= detail::kPatchedCode) special.push_back(v);
    // Width 0 for special sections: reads nothing past their start (inside the payload).
    const std::uint32_t w = code < detail::kPatchedCode ? code : 0;
    const std::uint32_t z = detail::read_bits_branchless(data, p.blocks.section_start(v) + std::uint64_t(t) * w, w);
    // Code 0 (all zero) leaves the VQ value untouched, as decode_window does (keeps -0.0f).
    const float with_residual = out[v] + float(detail::unzigzag(z)) * step;
    out[v] = w ? with_residual : out[v];
  }
  for (const std::uint64_t v : special) {
    const std::uint64_t pos = p.blocks.section_start(v);
    if (p.blocks.width(v) == detail::kPatchedCode)
      out[v] = out[v] + float(detail::unzigzag(patched_value(data, pos, pb, t))) * step;
    else
      out[v] = detail::bits_float(detail::read_bits(data, pos + 32ull * t, 32));
  }
}

// k_t of a predictive section from k_0 and its prediction errors (O(t): each value depends on
// the ones before it), and k_{t-1} in *previous. `scratch` holds step_count integers.
std::int32_t predictive_k(const EncodedPage& p, const std::uint8_t* data, const detail::VertexSection& s,
                          std::uint32_t t, std::uint32_t* scratch, std::int32_t* previous = nullptr) {
  std::int32_t k = std::int32_t(s.first_value), k2 = k;
  if (t > 0) detail::all_values(data, s.values, p.step_count - 1, scratch);
  for (std::uint32_t i = 1; i <= t; ++i) {
    const std::int32_t next = detail::next_k(s.predictor, i, k, k2, detail::unzigzag(scratch[i - 1]));
    k2 = k;
    k = next;
  }
  if (previous) *previous = k2;
  return k;
}

// All steps of one vertex from its section; `out` holds the VQ base (vq_residual), stride apart.
void section_all(const EncodedPage& p, const std::uint8_t* data, const detail::VertexSection& s, float* out,
                 std::uint64_t stride, std::uint32_t* scratch) {
  const std::uint32_t n = p.step_count;
  if (s.code == BitBlocks::kRawWidth) {
    for (std::uint32_t t = 0; t < n; ++t)
      out[t * stride] = detail::bits_float(detail::read_bits(data, s.start + 32ull * t, 32));
  } else if (p.method == PageMethod::predictive) {
    detail::all_values(data, s.values, n - 1, scratch);
    std::int32_t k = std::int32_t(s.first_value), k2 = k;
    out[0] = p.quantiser.lo + float(k) * p.quantiser.step;
    for (std::uint32_t t = 1; t < n; ++t) {
      const std::int32_t next = detail::next_k(s.predictor, t, k, k2, detail::unzigzag(scratch[t - 1]));
      k2 = k;
      k = next;
      out[t * stride] = p.quantiser.lo + float(k) * p.quantiser.step;
    }
  } else if (s.values.width || s.values.exceptions) {
    detail::all_values(data, s.values, n, scratch);
    for (std::uint32_t t = 0; t < n; ++t)
      out[t * stride] = out[t * stride] + float(detail::unzigzag(scratch[t])) * p.quantiser.step;
  }
}

// Every step of the whole lane blocks of [b, e) of a plain-VQ page with a residual,
// kResidualChunk vertices at a time: their residual is unpacked first, then each VQ value is
// written with it added (vq_window), so that every row is written once, not written by the VQ
// pass and then read back and written again by the residual pass. Raw vertices are appended to
// `special`. Returns where it stopped (b where it does not apply). x86 kernels only.
#if PNB_X86_KERNELS
std::uint64_t vq_residual_lanes(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* out,
                                std::vector<std::uint64_t>& special) {
  // Checked before any chunk is unpacked, so that none is unpacked in vain.
  if (!detail::vq_window_applies(p.window) || p.step_count > detail::kResidualChunkSteps) return b;
  const std::uint64_t end = b + (e - b) / detail::kLanes * detail::kLanes;
  for (std::uint64_t v0 = b; v0 < end; v0 += detail::kResidualChunk) {
    const std::uint64_t lanes = std::min(detail::kResidualChunk, end - v0);
    const detail::ResidualLanes r = detail::unpack_residual_lanes(p, v0, lanes, special);
    // Should it not apply, the caller decodes the rest; raw vertices this chunk listed are
    // decoded again there, to the same values.
    if (!detail::vq_window(p.means.lo, p.means.scale, p.means.q.data() + v0, p.vq.c8.data(), p.vq.i8.data() + v0,
                           p.vq.cw.data(), p.window, p.vq.iw.data() + v0, lanes, out + v0, p.vertex_count, p.step_count,
                           &r))
      return v0;
  }
  return end;
}
#endif  // PNB_X86_KERNELS

// Every step of vertices [from, e) of a page.
void window_range(const EncodedPage& p, std::uint64_t from, std::uint64_t e, float* out) {
  const std::uint64_t N = p.vertex_count;
  const std::uint32_t n = p.step_count;
  thread_local std::vector<std::uint64_t> scalar;
  scalar.clear();
#if PNB_X86_KERNELS
  const std::uint64_t b = is_vq(p) && has_residual(p) ? vq_residual_lanes(p, from, e, out, scalar) : from;
#else
  const std::uint64_t b = from;
#endif
  if (b < e && is_vq(p) && !detail::vq_window(p.means.lo, p.means.scale, p.means.q.data() + b, p.vq.c8.data(),
                                     p.vq.i8.data() + b, p.vq.cw.data(), p.window, p.vq.iw.data() + b, e - b, out + b, N, n)) {
    // mean + D8 is constant over each of the 8 blocks of steps: computed once per block,
    // then each step adds its D_W value (same float operations as vq_value), eight steps at a
    // time where they share a block.
    thread_local std::vector<float> base;
    thread_local std::vector<std::int32_t> row;
    base.resize(e - b);
    row.resize(e - b);
    for (std::uint64_t v = b; v < e; ++v) row[v - b] = std::int32_t(p.vq.iw[v]) * std::int32_t(p.window);
    const std::uint32_t block = p.window / 8;
    for (std::uint32_t t = 0; t < n;) {
      if (t % block == 0)
        detail::mean_plus_entries(p.means.lo, p.means.scale, p.means.q.data() + b, p.vq.c8.data() + t / block,
                                  p.vq.i8.data() + b, e - b, base.data());
      // Eight steps that share a block, read as eight floats of each row (t + 8 <= W keeps the
      // read inside it; a partial window's last steps take a short group).
      if (block % 8 == 0 && t % 8 == 0 && t + 8 <= p.window) {
        const std::uint32_t steps = std::min<std::uint32_t>(8, n - t);
        detail::add_rows8(p.vq.cw.data() + t, row.data(), base.data(), e - b, out + std::uint64_t(t) * N + b, N, steps);
        t += steps;
      } else {
        detail::add_entries(p.vq.cw.data() + t, std::int32_t(p.window), p.vq.iw.data() + b, base.data(), e - b,
                            out + std::uint64_t(t) * N + b);
        ++t;
      }
    }
  }
  if (is_aligned(p)) {
    // Level and entry offset of each vertex once; then one lookup and add per value.
    thread_local std::vector<float> level;
    thread_local std::vector<std::int32_t> offset;
    level.resize(e - b);
    offset.resize(e - b);
    const std::int32_t D = std::int32_t(2 * p.window - 1);
    for (std::uint64_t v = b; v < e; ++v) {
      level[v - b] = detail::dequantise_mean(p.means.lo, p.means.scale, p.means.q[v]);
      offset[v - b] = std::int32_t(p.aligned.ia[v]) * D - std::int32_t(p.aligned.shift[v]);
    }
    for (std::uint32_t t = 0; t < n;) {
      // A row holds 2W - 1 values and a vertex's frame starts at most W - 1 into it, so eight
      // values from step t stay inside while t + 8 <= W.
      if (t + 8 <= p.window) {
        const std::uint32_t steps = std::min<std::uint32_t>(8, n - t);
        detail::add_rows8(p.aligned.ca.data() + (p.window - 1 + t), offset.data(), level.data(), e - b,
                          out + std::uint64_t(t) * N + b, N, steps);
        t += steps;
      } else {
        detail::add_offsets(p.aligned.ca.data() + (p.window - 1 + t), offset.data(), level.data(), e - b,
                            out + std::uint64_t(t) * N + b);
        ++t;
      }
    }
  }
  if (!has_residual(p) && p.method != PageMethod::predictive) return;
  thread_local std::vector<std::uint32_t> scratch;
  scratch.resize(n);
  std::uint64_t v = b;
#if PNB_X86_KERNELS
  if (detail::lanes_active()) {
    v = b + (e - b) / detail::kLanes * detail::kLanes;
    if (p.method == PageMethod::predictive)
      detail::predictive_window_lanes(p, b, v, out, scalar);
    else
      detail::residual_window_lanes(p, b, v, out, scalar);
  }
#endif
  for (; v < e; ++v) scalar.push_back(v);
  detail::VertexSection s;
  for (const std::uint64_t u : scalar) {
    detail::parse_vertex(p, p.blocks.payload.data(), p.blocks.section_start(u), p.blocks.width(u), kNoLimit, s);
    section_all(p, p.blocks.payload.data(), s, out + u, N, scratch.data());
  }
}

}  // namespace

namespace detail {

void predictive_step_range(const EncodedPage& p, std::uint32_t t, std::uint64_t b, std::uint64_t e, float* out,
                           std::int32_t* k1, std::int32_t* k2) {
  const std::uint8_t* data = p.blocks.payload.data();
  thread_local std::vector<std::uint32_t> scratch;
  scratch.resize(p.step_count);
  VertexSection s;
  for (std::uint64_t v = b; v < e; ++v) {
    const std::uint64_t pos = p.blocks.section_start(v);
    if (p.blocks.width(v) == BitBlocks::kRawWidth) {
      out[v] = bits_float(read_bits(data, pos + 32ull * t, 32));
      continue;
    }
    if (t == 0) {
      // k_0 is stored as is (after the predictor bit): no parse (playback's usual start).
      const auto k = std::int32_t(read_bits(data, pos + 1, p.quantiser.first_width));
      out[v] = p.quantiser.lo + float(k) * p.quantiser.step;
      if (k1) k1[v] = k2[v] = k;
      continue;
    }
    parse_vertex(p, data, pos, p.blocks.width(v), kNoLimit, s);
    std::int32_t previous;
    const std::int32_t k = compression::predictive_k(p, data, s, t, scratch.data(), &previous);
    out[v] = p.quantiser.lo + float(k) * p.quantiser.step;
    if (k1) k1[v] = k, k2[v] = previous;
  }
}


void vq_base_step(const EncodedPage& p, std::uint32_t t, std::uint64_t b, std::uint64_t e, float* out) {
  if (is_vq(p))
    vq_step_values(p.means.lo, p.means.scale, p.means.q.data() + b, p.vq.c8.data() + t / (p.window / 8), p.vq.i8.data() + b,
                   p.vq.cw.data() + t, std::int32_t(p.window), p.vq.iw.data() + b, e - b, out + b);
  else  // each vertex reads its aligned entry at frame position t + W - 1 - shift
    aligned_step_values(p.means.lo, p.means.scale, p.means.q.data() + b, p.aligned.ca.data() + (p.window - 1 + t),
                        p.aligned.ia.data() + b, p.aligned.shift.data() + b, std::int32_t(2 * p.window - 1), e - b, out + b);
}

}  // namespace detail

void detail::require_decodable(const EncodedPage& p, const char* call) {
  // Messages are built only on failure: the decoders call this for every step.
  const auto fail = [&](const std::string& what) { throw Error(ErrorCode::invalid_argument, std::string(call) + ": " + what); };
  const std::uint64_t N = p.vertex_count, K = p.codebook_size, W = p.window;
  const auto sized = [&](std::uint64_t have, std::uint64_t want, const char* what) {
    if (have != want) fail(std::string(what) + " holds " + std::to_string(have) + " values; expected " + std::to_string(want));
  };
  if (std::uint32_t(p.method) > kMaxMethod) fail("unknown page method " + std::to_string(std::uint32_t(p.method)));
  if (!valid_window(W)) fail("window " + std::to_string(W) + " is not a multiple of 8 in [8, 1024]");
  if (p.step_count < 1 || p.step_count > W) fail("step count " + std::to_string(p.step_count) + " outside 1..window");
  if (uses_plain_vq(p.method) || uses_aligned_vq(p.method)) {
    if (!valid_codebook_size(K)) fail("codebook size " + std::to_string(K) + " outside 2..256");
    sized(p.means.q.size(), N, "mean_q");
  }
  if (uses_plain_vq(p.method)) {
    sized(p.vq.c8.size(), K * 8, "c8");
    sized(p.vq.cw.size(), K * W, "cw");
    sized(p.vq.i8.size(), N, "i8");
    sized(p.vq.iw.size(), N, "iw");
  }
  if (uses_aligned_vq(p.method)) {
    if (W > kMaxAlignedWindow) fail("shift-aligned page with a window over 256 steps");
    sized(p.aligned.ca.size(), K * (2 * W - 1), "ca");
    sized(p.aligned.shift.size(), N, "shift");
    sized(p.aligned.ia.size(), N, "ia");
  }
  if (has_bit_blocks(p.method)) {
    const std::uint64_t groups = (N + kGroup - 1) / kGroup;
    sized(p.blocks.widths.size(), (N + 1) / 2, "widths");
    sized(p.blocks.section_bits.size(), N, "section_bits");
    sized(p.blocks.group_offsets.size(), groups + 1, "group_offsets");
    if (p.blocks.payload.size() < 8 || p.blocks.group_offsets.back() > p.blocks.payload.size() - 8)
      fail("bit payload shorter than its groups plus 8 bytes of padding");
  }
  if (p.method == PageMethod::predictive_lanes) {
    const LaneBlocks& L = p.lanes;
    const std::uint64_t B = lane_block_count(N);
    sized(L.widths.size(), kLaneWidths * B, "lane widths");
    sized(L.transient_ends.size(), B, "lane transient ends");
    for (const auto* table : {&L.linear, &L.raw, &L.exception_rows}) sized(table->size(), B, "lane block table");
    for (const auto* starts : {&L.bit_start, &L.raw_start, &L.row_start, &L.high_start})
      sized(starts->size(), B + 1, "lane block starts");
    sized(L.exception_steps.size(), L.row_start.back(), "exception_steps");
    sized(L.exception_lanes.size(), L.row_start.back(), "exception_lanes");
    sized(L.highs.size(), L.high_start.back(), "highs");
    sized(L.raw_values.size(), L.raw_start.back(), "raw_values");
    sized(L.words.size(), lane_words_held(L.bit_start.back()), "lane words");
  }
}

void validate_page(const EncodedPage& p) {
  detail::require_decodable(p, "validate_page");
  require(p.times.size() == p.step_count, "validate_page: " + std::to_string(p.times.size()) + " time values for " +
                                              std::to_string(p.step_count) + " steps");
  const std::string error = detail::page_contents_error(p, nullptr);
  require(error.empty(), "validate_page: " + error);
}

void decode_step(const EncodedPage& p, std::uint32_t t, float* out) {
  detail::require_decodable(p, "decode_step");
  require(out != nullptr, "decode_step: null output");
  require(t < p.step_count, "decode_step: step " + std::to_string(t) + " is outside the page's " +
                                std::to_string(p.step_count) + " steps");
  const std::uint64_t N = p.vertex_count;
  if (p.method == PageMethod::predictive_lanes) {
    parallel_for(detail::lane_block_count(N), kStepChunk / 4 / detail::kLaneBlock,
                 [&](std::size_t b, std::size_t e) { detail::lane_blocks_step(p, t, b, e, out); });
    return;
  }
  if (p.method == PageMethod::predictive) {
    parallel_for(N, kStepChunk / 4,
                 [&](std::size_t b, std::size_t e) { detail::predictive_step_range(p, t, b, e, out); });
    return;
  }
  // VQ base and residual in one pass per chunk, while the chunk's outputs are in cache.
  const std::size_t chunk = has_residual(p) ? kStepChunk / 8 : is_vq(p) ? kStepChunk : kStepChunk / 4;
  parallel_for(N, chunk, [&](std::size_t b, std::size_t e) {
    detail::vq_base_step(p, t, b, e, out);
    if (has_residual(p)) residual_step_range(p, t, b, e, out);
  });
}

void decode_window(const EncodedPage& p, float* out) {
  detail::require_decodable(p, "decode_window");
  require(out != nullptr, "decode_window: null output");
  const std::uint64_t N = p.vertex_count;
  // Chunks of whole groups: each writes its vertex range of every step row. A page smaller than
  // a chunk stays whole. Split between the threads, mug's predictive page (3774 vertices x 21
  // steps, about 35 us) decoded up to twice as fast with the other worker awake, but with another
  // process busy on the other core some runs took four times as long (2.2 against 8.8 GB/s): a
  // descheduled worker holding a chunk keeps the caller waiting about 100 us.
  constexpr std::uint64_t kChunk = kGroup * 64;
  if (p.method == PageMethod::predictive_lanes) {
    parallel_for(detail::lane_block_count(N), kChunk / detail::kLaneBlock,
                 [&](std::size_t b, std::size_t e) { detail::lane_blocks_window(p, b, e, out); });
    return;
  }
  parallel_for(N, kChunk, [&](std::size_t b, std::size_t e) {
    const std::uint64_t run = has_residual(p) ? kResidualRun : e - b;
    for (std::uint64_t s = b; s < e; s += run) window_range(p, s, std::min<std::uint64_t>(e, s + run), out);
  });
}

void decode_vertex(const EncodedPage& p, std::uint64_t v, float* out) {
  detail::require_decodable(p, "decode_vertex");
  require(out != nullptr, "decode_vertex: null output");
  require(v < p.vertex_count, "decode_vertex: vertex " + std::to_string(v) + " is outside the page's " +
                                  std::to_string(p.vertex_count) + " vertices");
  if (p.method == PageMethod::predictive_lanes) {
    detail::lane_blocks_vertex(p, v, out);
    return;
  }
  if (is_vq(p)) {
    std::vector<float> series(p.window);
    detail::vq_series(detail::dequantise_mean(p.means.lo, p.means.scale, p.means.q[v]), p.vq.c8.data() + std::size_t(p.vq.i8[v]) * 8,
                      p.vq.cw.data() + std::size_t(p.vq.iw[v]) * p.window, p.window, series.data());
    std::copy(series.begin(), series.begin() + p.step_count, out);
  }
  if (is_aligned(p))
    detail::aligned_series(detail::dequantise_mean(p.means.lo, p.means.scale, p.means.q[v]),
                           p.aligned.ca.data() + std::size_t(p.aligned.ia[v]) * (2 * p.window - 1), p.window, p.aligned.shift[v], p.step_count,
                           out);
  if (!has_residual(p) && p.method != PageMethod::predictive) return;
  detail::VertexSection s;
  std::vector<std::uint32_t> scratch(p.step_count);
  detail::parse_vertex(p, p.blocks.payload.data(), p.blocks.section_start(v), p.blocks.width(v), kNoLimit, s);
  section_all(p, p.blocks.payload.data(), s, out, 1, scratch.data());
}

}  // namespace penumbra::compression
