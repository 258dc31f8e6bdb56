// SPDX-License-Identifier: BSD-3-Clause
// compression/include/penumbra/compression/encoded_page.h
#pragma once
#include <cstdint>
#include <vector>

#include "penumbra/compression/codec_params.h"
#include "penumbra/compression/value_map.h"
#include "penumbra/core/aligned_allocator.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::compression {

/// Small bit-packed blocks of per-vertex integers, one block per vertex-window, so that any
/// vertex stays randomly accessible: vertices are grouped by kGroupSize; each group's bits
/// start at a byte offset, and a 4-bit width per vertex says how many bits each of its values
/// takes (width kRawWidth: the vertex's values are stored as exact float32 instead).
struct BitBlocks {
  static constexpr std::uint32_t kGroupSize = 128;
  static constexpr std::uint32_t kRawWidth = 15;
  std::vector<std::uint64_t> group_offsets;  ///< byte offset of each group, plus the end
  std::vector<std::uint8_t> widths;          ///< two 4-bit widths per byte, low nibble first
  std::vector<std::uint8_t> payload;         ///< bits, LSB first; 8 bytes of padding at the end
  /// Derived, not stored in the file (filled by the encoder and by the page parser, which
  /// walks every section anyway): bit offset of each vertex's section from its group's
  /// start. It makes one step of one vertex an O(1) read (known offset and width) instead of
  /// a walk over the group, for 4 bytes per vertex of memory.
  std::vector<std::uint32_t> section_bits;

  std::uint32_t width(std::uint64_t vertex) const {
    return (widths[vertex >> 1] >> ((vertex & 1) * 4)) & 0xF;
  }
  std::uint64_t section_start(std::uint64_t vertex) const {
    return group_offsets[vertex / kGroupSize] * 8 + section_bits[vertex];
  }
  bool empty() const { return group_offsets.empty(); }
};

/// The predictive coder's integers in blocks of 16 neighbouring vertices
/// (PageMethod::predictive_lanes; layout in compression/src/lane_blocks.h). The values of a
/// block share their widths and are interleaved across its 16 lanes, so one step of a block is
/// one uniform shift of a row of 16 words: no per-vertex offsets, widths or loads.
struct LaneBlocks {
  static constexpr std::uint32_t kLanes = 16;
  std::vector<std::uint8_t> widths;        ///< per block: the widths of step 1, step 2, the transient steps and the later steps, and the exceptions' high-part width
  std::vector<std::uint8_t> transient_ends;  ///< per block: its first step past the transient steps T, min(steps, 3) <= T <= steps
  std::vector<std::uint16_t> linear;       ///< per block: lanes whose predictor extrapolates (bit l: lane l)
  std::vector<std::uint16_t> raw;          ///< per block: lanes stored as exact float32 values instead
  std::vector<std::uint16_t> exception_rows;  ///< per block: steps with an exception
  std::vector<std::uint16_t> exception_steps;  ///< per exception row: its step, increasing within a block
  std::vector<std::uint16_t> exception_lanes;  ///< per exception row: its lanes (nonzero)
  std::vector<std::uint8_t> exception_bits;    ///< high parts, each block's at its width, LSB first; 8 bytes of padding
  std::vector<float> raw_values;               ///< raw lanes' values, block by block, lane by lane, step by step
  /// A zero row (in memory only, not in the file), then rows of 16 words: lane l's bits run down
  /// column l; one spare row. Rows start on cache lines, and the zero row lets a vector decoder
  /// read the row below any slot's last bit.
  std::vector<std::uint32_t, AlignedAllocator<std::uint32_t, 64>> words;
  /// Derived when a page is built or parsed, not stored: where each block starts (its bit in
  /// every lane's column, its first exception row, high part and raw value), plus the end, and
  /// the high parts unpacked to 32 bits.
  std::vector<std::uint64_t> bit_start, raw_start, row_start, high_start;
  std::vector<std::uint32_t> highs;

  std::uint64_t block_count() const { return linear.size(); }
  bool empty() const { return linear.empty(); }
};

/// Per-vertex 16-bit values over the window's range: mean(v) = lo + float(q[v]) * scale. The
/// vertices' means on vq pages, their levels on vq_aligned pages.
struct VertexMeans {
  float lo = 0, scale = 0;
  std::vector<std::uint16_t> q;
};

/// vq, vq_residual: the D8 and D_W codebooks and each vertex's entries in them.
struct VqCodebooks {
  std::vector<float> c8;  ///< codebook_size x 8
  std::vector<float> cw;  ///< codebook_size x window
  std::vector<std::uint8_t> i8, iw;
};

/// vq_aligned, vq_aligned_residual: one codebook over frames of 2 window - 1 steps, and each
/// vertex's shift and entry.
struct AlignedCodebook {
  std::vector<float> ca;             ///< codebook_size x (2 window - 1): ca_lo + float(ca_q) * ca_scale
  std::vector<std::uint16_t> ca_q;   ///< the codebook as stored
  float ca_lo = 0, ca_scale = 0;
  std::vector<std::uint8_t> shift;   ///< step at which the vertex's entry is aligned, < step_count
  std::vector<std::uint8_t> ia;      ///< entry of ca
};

/// The integer grid of the residual (vq_residual, vq_aligned_residual: q, zigzag) and of the
/// predictive coder (predictive, predictive_lanes: k, zigzag deltas).
struct Quantiser {
  float step = 0;
  float lo = 0;                   ///< predictive: value of k = 0
  std::uint32_t first_width = 0;  ///< predictive: bits of k_0
};

/// One window of one field, decoded from (or about to be written as) one page.
/// Reconstruction of step t (0 <= t < step_count) at vertex v, in float, in this order:
///   vq:           ((mean(v) + c8[i8[v]][t / (window/8)]) + cw[iw[v]][t])
///   vq_residual:  vq + float(q) * step, or the stored exact value for raw vertices
///   vq_aligned:   mean(v) + ca[ia[v]][t + window - 1 - shift[v]]  (mean(v) is the level)
///   vq_aligned_residual: vq_aligned + float(q) * step, or raw values
///   predictive, predictive_lanes: lo + float(k_t) * step, k_t = k_0 + sum of deltas, or exact raw values
/// with mean(v) from `means`. These are the stored values; the field's values are
/// map.value(stored) (ValueMap; the identity for float32 input). A page holds only its method's
/// members; the others stay empty.
struct EncodedPage {
  PageMethod method = PageMethod::vq;
  std::uint64_t first_step = 0;
  std::uint32_t step_count = 0;
  std::uint32_t window = 0;
  std::uint32_t codebook_size = 0;
  std::uint64_t vertex_count = 0;
  std::vector<double> times;  ///< time value of each of the step_count steps
  ValueMap map;               ///< from stored values to the field's (format version 7)
  float value_min = 0, value_max = 0;  ///< of the stored values
  /// Error bound this page holds at every stored value (0: none); map.scale x bound in the field's units.
  float bound = 0;
  /// Why `method` was chosen (recorded in the page header): VQ's signal-to-noise ratio on
  /// the training sample, and the estimated bytes of VQ (+ residual) and of the predictive coder.
  float sample_snr_db = 0, vq_bytes_estimate = 0, predictive_bytes_estimate = 0;

  VertexMeans means;        ///< vq and vq_aligned pages, with or without a residual
  VqCodebooks vq;           ///< vq, vq_residual
  AlignedCodebook aligned;  ///< vq_aligned, vq_aligned_residual
  Quantiser quantiser;      ///< every page with a residual, and predictive pages
  BitBlocks blocks;         ///< vq_residual, vq_aligned_residual, predictive
  LaneBlocks lanes;         ///< predictive_lanes

  /// Bytes this page holds in memory (what a pager counts against its cap).
  std::uint64_t resident_bytes() const;
};

/// Calls f(a.x, b.x, ...) for every array x of an EncodedPage, the same member of each page at
/// once: the one list of a page's arrays, for what must reach all of them.
template <class F, class... Pages>
void for_each_array(F&& f, Pages&... p) {
  f(p.times...), f(p.vq.c8...), f(p.vq.cw...), f(p.means.q...), f(p.vq.i8...), f(p.vq.iw...);
  f(p.aligned.ca...), f(p.aligned.ca_q...), f(p.aligned.shift...), f(p.aligned.ia...);
  f(p.blocks.group_offsets...), f(p.blocks.widths...), f(p.blocks.payload...), f(p.blocks.section_bits...);
  f(p.lanes.widths...), f(p.lanes.transient_ends...), f(p.lanes.linear...), f(p.lanes.raw...);
  f(p.lanes.exception_rows...), f(p.lanes.exception_steps...), f(p.lanes.exception_lanes...);
  f(p.lanes.exception_bits...), f(p.lanes.raw_values...), f(p.lanes.words...);
  f(p.lanes.bit_start...), f(p.lanes.raw_start...), f(p.lanes.row_start...), f(p.lanes.high_start...);
  f(p.lanes.highs...);
}

}  // namespace penumbra::compression

PNB_PUBLIC_END
