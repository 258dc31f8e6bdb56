// SPDX-License-Identifier: BSD-3-Clause
// compression/src/lane_blocks_decoder.cpp -- decoders of predictive_lanes pages: a scalar one
// that every path can use, and AVX-512 window and cursor decoders that are bit-identical to it
// (the AVX2 ones are in lane_blocks_avx2.cpp). The vector decoders exist only where
// PNB_X86_KERNELS is 1 (cpu_features.h); elsewhere every decode takes the scalar one.
#include <algorithm>
#include <atomic>
#include <bit>
#include <type_traits>

#include "cpu_features.h"
#include "lane_blocks.h"
#include "section_lanes.h"
#include "target_region.h"
#if PNB_X86_KERNELS
#include <immintrin.h>
#endif

namespace penumbra::compression::detail {

void lane_block_begin(const EncodedPage& p, std::uint64_t b, LaneBlockState& s) {
  const LaneBlocks& L = p.lanes;
  s.t = 0;
  s.pos = L.bit_start[b];
  s.row = L.row_start[b];
  s.high = L.high_start[b];
}

void lane_block_step(const EncodedPage& p, std::uint64_t b, LaneBlockState& s) {
  const LaneBlocks& L = p.lanes;
  const std::uint32_t* rows = lane_rows(L);
  const std::uint32_t t = s.t;
  if (t == 0) {
    for (std::uint32_t l = 0; l < kLaneBlock; ++l) s.k1[l] = s.k2[l] = lane_slot(rows, s.pos, l, p.quantiser.first_width);
    s.pos += p.quantiser.first_width;
    s.t = 1;
    return;
  }
  const std::uint32_t width = lane_step_width(L, b, t);
  std::uint32_t error[kLaneBlock];
  for (std::uint32_t l = 0; l < kLaneBlock; ++l) error[l] = sign_extend(lane_slot(rows, s.pos, l, width), width);
  if (exception_row_due(L, b, s)) {
    for (std::uint32_t lanes = L.exception_lanes[s.row++]; lanes; lanes &= lanes - 1)
      error[std::countr_zero(lanes)] += std::uint32_t(std::uint64_t(L.highs[s.high++]) << width);
  }
  const std::uint16_t linear = t >= 2 ? L.linear[b] : 0;
  for (std::uint32_t l = 0; l < kLaneBlock; ++l) {
    const std::uint32_t prediction = (linear >> l & 1) ? 2u * s.k1[l] - s.k2[l] : s.k1[l];
    s.k2[l] = s.k1[l];
    s.k1[l] = prediction + error[l];
  }
  s.pos += width;
  ++s.t;
}

namespace {

// Step t of block b's raw lanes into row[lane].
void write_raw_step(const EncodedPage& p, std::uint64_t b, std::uint32_t t, float* row) {
  const LaneBlocks& L = p.lanes;
  const float* raw = L.raw_values.data() + L.raw_start[b];
  for (std::uint32_t m = L.raw[b]; m; m &= m - 1, raw += p.step_count) row[std::countr_zero(m)] = raw[t];
}

}  // namespace

void lane_block_write(const EncodedPage& p, std::uint64_t b, const LaneBlockState& s, float* row) {
  const std::uint64_t lanes = lane_block_lanes(p.vertex_count, b);
  for (std::uint64_t l = 0; l < lanes; ++l) row[l] = p.quantiser.lo + float(std::int32_t(s.k1[l])) * p.quantiser.step;
  write_raw_step(p, b, s.t - 1, row);
}

namespace {

#if PNB_X86_KERNELS
// The raw lanes of blocks [b, e), every step (after the vector decoder wrote their slots' zeros).
void write_raw_lanes(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window) {
  const LaneBlocks& L = p.lanes;
  const std::uint64_t N = p.vertex_count;
  const std::uint32_t n = p.step_count;
  for (std::uint64_t k = b; k < e; ++k) {
    const float* raw = L.raw_values.data() + L.raw_start[k];
    for (std::uint32_t m = L.raw[k]; m; m &= m - 1, raw += n) {
      float* out = window + k * kLaneBlock + std::countr_zero(m);
      for (std::uint32_t t = 0; t < n; ++t) out[std::uint64_t(t) * N] = raw[t];
    }
  }
}
#endif  // PNB_X86_KERNELS

void scalar_window(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window) {
  const std::uint64_t N = p.vertex_count;
  LaneBlockState s;
  for (std::uint64_t k = b; k < e; ++k) {
    lane_block_begin(p, k, s);
    for (std::uint32_t t = 0; t < p.step_count; ++t) {
      lane_block_step(p, k, s);
      lane_block_write(p, k, s, window + std::uint64_t(t) * N + k * kLaneBlock);
    }
  }
}

std::atomic<int> g_lane_isa_cap{int(LaneIsa::avx512_vbmi2)};

#if PNB_X86_KERNELS
// GCC 12 warns that the AVX-512 intrinsics' own undefined-vector placeholders may be used
// uninitialised (a false positive inside immintrin.h).
#pragma GCC diagnostic push
#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
PNB_TARGET_REGION_BEGIN("avx512f")
// The 32 bits of every lane's column that end at bit `end`: from the row `end` lies in and the row
// below it (the page's zero row below row 0). A slot of width w that ends there is their top w
// bits, so one arithmetic shift both extracts it and extends its sign: no mask. Two shifts and
// an or, for any AVX-512 CPU.
struct TwoShifts {
  static __m512i bits_ending(const std::uint32_t* rows, std::uint64_t end) {
    const std::uint32_t* r = row_holding(rows, end);
    const std::uint32_t sh = std::uint32_t(end & 31);
    return _mm512_or_si512(_mm512_srl_epi32(_mm512_loadu_si512(r - kLaneBlock), _mm_cvtsi32_si128(int(sh))),
                           _mm512_sll_epi32(_mm512_loadu_si512(r), _mm_cvtsi32_si128(int(32 - sh))));
  }
  // A span's slots of one width, one step after another.
  class Reader {
   public:
    Reader(const std::uint32_t* rows, std::uint64_t end, std::uint32_t width) : m_rows(rows), m_end(end), m_width(width) {}
    __m512i next() {
      m_end += m_width;
      return bits_ending(m_rows, m_end);
    }
    std::uint64_t end() const { return m_end; }

   private:
    const std::uint32_t* m_rows;
    std::uint64_t m_end;
    std::uint32_t m_width;
  };
};

inline __m512 values512(__m512 lo, __m512 step, __m512i k) {
  return _mm512_add_ps(lo, _mm512_mul_ps(_mm512_cvtepi32_ps(k), step));
}

// A block's values: a whole vector for a full block (cheaper than a masked store), the real lanes
// of the last.
inline void put512(float* out, __mmask16 lanes, __m512 v) {
  if (lanes == 0xFFFF)
    _mm512_storeu_ps(out, v);
  else
    _mm512_mask_storeu_ps(out, lanes, v);
}

// Adds exception row `row`'s high parts to its lanes of the errors e, moving row and high on.
inline __m512i patch512(const std::uint16_t* exception_lanes, const std::uint32_t* highs, std::uint64_t& row,
                        std::uint64_t& high, std::uint32_t width, __m512i e) {
  const __mmask16 lanes = exception_lanes[row++];
  const __m512i h = _mm512_maskz_expandloadu_epi32(lanes, highs + high);
  high += std::uint32_t(std::popcount(std::uint32_t(lanes)));
  return _mm512_add_epi32(e, _mm512_sll_epi32(h, _mm_cvtsi32_si128(int(width))));
}

// A block's exception rows: where its next row and high part are, and that row's step. (Plain
// pointers rather than the page's vectors: after a vector store, which may alias anything, a
// vector's data pointer would be loaded again.)
struct BlockRows {
  const std::uint16_t *steps, *lanes;
  const std::uint32_t* highs;
  std::uint64_t row, row_end, high;
  std::uint32_t next;  // 0: no row left (none lies at step 0)
  static BlockRows of(const LaneBlocks& L, std::uint64_t b) {
    const std::uint64_t row = L.row_start[b], row_end = L.row_start[b + 1];
    return {L.exception_steps.data(),
            L.exception_lanes.data(),
            L.highs.data(),
            row,
            row_end,
            L.high_start[b],
            next_exception_step(L.exception_steps.data(), row, row_end)};
  }
  // e plus the high parts, at `width`, of the block's row at step t if it has one there.
  __m512i add(std::uint32_t t, std::uint32_t width, __m512i e) {
    if (next != t) return e;
    e = patch512(lanes, highs, row, high, width, e);
    next = next_exception_step(steps, row, row_end);
    return e;
  }
};

PNB_TARGET_REGION_END

// The templates below are defined where VBMI2 is allowed, so that their FunnelShift instances may
// use it: a template is compiled for the target of its definition. Their TwoShifts instances,
// which CPUs without VBMI2 run, use no VBMI2 instruction (the ctest
// LaneBlocks.NoVbmi2WhereItMayBeMissing checks the object code).
PNB_TARGET_REGION_BEGIN("avx512f,avx512vbmi2")
// The same 32 bits by one funnel shift, on CPUs with AVX-512 VBMI2 (4-7 % faster on mug).
struct FunnelShift {
  // `shift`: end % 32 in every lane (the funnel shift reads only a count's low 5 bits).
  static __m512i funnel(const std::uint32_t* rows, std::uint64_t end, __m512i shift) {
    const std::uint32_t* r = row_holding(rows, end);
    return _mm512_shrdv_epi32(_mm512_loadu_si512(r - kLaneBlock), _mm512_loadu_si512(r), shift);
  }
  static __m512i bits_ending(const std::uint32_t* rows, std::uint64_t end) {
    return funnel(rows, end, _mm512_set1_epi32(int(end & 31)));
  }
  // Keeps the shift in a vector and adds the width at each step: the funnel shift reads only the
  // count's low 5 bits, so the count may run past 31, and no scalar goes to a vector per step.
  class Reader {
   public:
    Reader(const std::uint32_t* rows, std::uint64_t end, std::uint32_t width)
        : m_rows(rows), m_end(end), m_width(width), m_shift(_mm512_set1_epi32(int(end))), m_step(_mm512_set1_epi32(int(width))) {}
    __m512i next() {
      m_end += m_width;
      m_shift = _mm512_add_epi32(m_shift, m_step);
      return funnel(m_rows, m_end, m_shift);
    }
    std::uint64_t end() const { return m_end; }

   private:
    const std::uint32_t* m_rows;
    std::uint64_t m_end;
    std::uint32_t m_width;
    __m512i m_shift, m_step;
  };
};

// k_0: the unsigned `width`-bit slots ending at `end` (width 0: zeros, a shift by 32).
template <class Bits>
__m512i first512(const std::uint32_t* rows, std::uint64_t end, std::uint32_t width) {
  return _mm512_srl_epi32(Bits::bits_ending(rows, end), _mm_cvtsi32_si128(int(32 - width)));
}

// The prediction errors in the `width`-bit two's-complement slots ending at `end`.
template <class Bits>
__m512i errors512(const std::uint32_t* rows, std::uint64_t end, std::uint32_t width) {
  if (width == 0) return _mm512_setzero_si512();
  return _mm512_sra_epi32(Bits::bits_ending(rows, end), _mm_cvtsi32_si128(int(32 - width)));
}

// One block at a time, all its steps: its state stays in registers (four blocks side by side
// spilled theirs, and ran 6 % slower in a prototype). Each step is two row loads, joined by a
// funnel shift (or two shifts and an or) and an arithmetic shift; an exception row adds its high
// parts, expanded into their lanes. Steps 1 and 2 are decoded one by one; the transient steps and
// the later ones each run a loop of their own, so that a step's width stays in a register; the
// loop is bound by the instructions it issues, so it keeps as few as it can (no store mask, no
// per-step shift count from a scalar).
// A span without an exception row does not look for one (on mug-diffused at 1e-3, 209 of 236
// blocks have no row at all), and a span of width 0 without rows holds
// k, or moves it by the extrapolating lanes' difference, without reading a slot. The block keeps
// k and its last difference d = k_t - k_{t-1}: the extrapolating lanes' next difference is d
// plus the error, the others' the error alone (one masked add), the same integers as k_{t-1} +
// prediction error.
// Bit-identical to lane_block_step: the same wrapping integers, then a multiply and an add that
// are never fused. Full: every lane of every block is a vertex (whole-vector stores). Block b's
// step t goes to to[t * N + 16 (c - b)].
template <class Bits, bool Full>
void avx512_window(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* to, std::uint64_t N) {
  const LaneBlocks& L = p.lanes;
  const std::uint32_t n = p.step_count, fw = p.quantiser.first_width;
  const std::uint32_t* rows = lane_rows(L);
  const __m512 lo = _mm512_set1_ps(p.quantiser.lo), step = _mm512_set1_ps(p.quantiser.step);
  for (std::uint64_t c = b; c < e; ++c) {
    const __mmask16 store = lane_block_mask(p.vertex_count, c), linear = L.linear[c];
    const auto put = [&](float* to, __m512 v) __attribute__((always_inline)) {
      if constexpr (Full)
        _mm512_storeu_ps(to, v);
      else
        _mm512_mask_storeu_ps(to, store, v);
      prefetch_row_ahead(to);
    };
    const std::uint32_t w1 = lane_width_1(L, c);
    std::uint64_t end = L.bit_start[c] + fw;
    BlockRows exceptions = BlockRows::of(L, c);
    float* out = to + (c - b) * kLaneBlock;
    __m512i k = first512<Bits>(rows, end, fw);
    put(out, values512(lo, step, k));
    if (n < 2) continue;
    out += N;
    end += w1;
    __m512i d = exceptions.add(1, w1, errors512<Bits>(rows, end, w1));
    k = _mm512_add_epi32(k, d);
    put(out, values512(lo, step, k));
    if (n < 3) continue;
    // Step 2, alone at its width: the first whose prediction may extrapolate.
    const std::uint32_t w2 = lane_width_2(L, c);
    out += N;
    end += w2;
    const __m512i error2 = exceptions.add(2, w2, errors512<Bits>(rows, end, w2));
    d = _mm512_mask_add_epi32(error2, linear, error2, d);
    k = _mm512_add_epi32(k, d);
    put(out, values512(lo, step, k));
    const auto steps = [&](const LaneStepSpan& span, auto rows_left, auto plain) __attribute__((always_inline)) {
      constexpr bool kRows = decltype(rows_left)::value, kPlain = decltype(plain)::value;
      const std::uint32_t w = span.width;
      const auto advance = [&](__m512i error) __attribute__((always_inline)) {
        out += N;
        if constexpr (kPlain) {
          k = _mm512_add_epi32(k, error);
        } else {
          d = _mm512_mask_add_epi32(error, linear, error, d);
          k = _mm512_add_epi32(k, d);
        }
        put(out, values512(lo, step, k));
      };
      if (w == 0) {
        if constexpr (!kRows) {
          d = _mm512_maskz_mov_epi32(linear, d);  // every error is 0
          if (_mm512_test_epi32_mask(d, d) == 0) {
            const __m512 v = values512(lo, step, k);
            for (std::uint32_t t = span.from; t < span.to; ++t) put(out += N, v);
            return;
          }
        }
        for (std::uint32_t t = span.from; t < span.to; ++t)
          advance(kRows ? exceptions.add(t, w, _mm512_setzero_si512()) : _mm512_setzero_si512());
        return;
      }
      // The count in every lane (a per-lane shift): a shift by one count in an xmm register is
      // two operations on Intel cores, one of them on the shuffle port (2-4 % on mug's pages).
      const __m512i spare = _mm512_set1_epi32(int(32 - w));
      typename Bits::Reader slots(rows, end, w);
      // Unrolled by 2: 1.01-1.015x over 4 on mug's lane pages (8: 0.96-0.98x).
#pragma GCC unroll 2
      for (std::uint32_t t = span.from; t < span.to; ++t) {
        const __m512i error = _mm512_srav_epi32(slots.next(), spare);
        advance(kRows ? exceptions.add(t, w, error) : error);
      }
      end = slots.end();
    };
    // Each span looks for exception rows only if it has one (a row's step is in it: the rows
    // before it were taken), and keeps no difference in a block without extrapolating lanes (k
    // plus the error: 1.5-5.6 % on mug's lane pages, more than half of whose blocks have none).
    const auto span = [&](const LaneStepSpan& s) __attribute__((always_inline)) {
      const bool rows_left = exceptions.next != 0 && exceptions.next < s.to;
      if (linear == 0)
        rows_left ? steps(s, std::true_type{}, std::true_type{}) : steps(s, std::false_type{}, std::true_type{});
      else
        rows_left ? steps(s, std::true_type{}, std::false_type{}) : steps(s, std::false_type{}, std::false_type{});
    };
    const auto spans = lane_step_spans(L, c, n);  // named calls: a loop over the two cost AVX2 7 %
    span(spans[1]);
    span(spans[2]);
  }
}

// One step of blocks [b, e) from their states (all at the same step, after step 0).
template <class Bits>
void avx512_next(const EncodedPage& p, std::uint64_t b, std::uint64_t e, LaneBlockState* states, float* out) {
  const LaneBlocks& L = p.lanes;
  const std::uint32_t* rows = lane_rows(L);
  const __m512 lo = _mm512_set1_ps(p.quantiser.lo), step = _mm512_set1_ps(p.quantiser.step);
  for (std::uint64_t k = b; k < e; ++k) {
    LaneBlockState& s = states[k];
    const std::uint32_t t = s.t, width = lane_step_width(L, k, t);
    s.pos += width;
    __m512i error = errors512<Bits>(rows, s.pos, width);
    if (exception_row_due(L, k, s))
      error = patch512(L.exception_lanes.data(), L.highs.data(), s.row, s.high, width, error);
    const __m512i k1 = _mm512_loadu_si512(s.k1), k2 = _mm512_loadu_si512(s.k2);
    const __m512i trend = _mm512_maskz_sub_epi32(t >= 2 ? L.linear[k] : 0, k1, k2);
    const __m512i next = _mm512_add_epi32(_mm512_add_epi32(k1, trend), error);
    _mm512_storeu_si512(s.k2, k1);
    _mm512_storeu_si512(s.k1, next);
    ++s.t;
    put512(out + k * kLaneBlock, lane_block_mask(p.vertex_count, k), values512(lo, step, next));
  }
}

// Blocks [b, e): the full ones, then the last if some of its lanes are padding.
template <class Bits>
void avx512_blocks(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window) {
  const std::uint64_t N = p.vertex_count, full_end = std::min(e, N / kLaneBlock);
  if (b < full_end) avx512_window<Bits, true>(p, b, full_end, window + b * kLaneBlock, N);
  if (std::max(b, full_end) < e)
    avx512_window<Bits, false>(p, std::max(b, full_end), e, window + std::max(b, full_end) * kLaneBlock, N);
}
PNB_TARGET_REGION_END
#pragma GCC diagnostic pop
#endif  // PNB_X86_KERNELS

}  // namespace

LaneIsa lane_isa() {
  static const LaneIsa cpu = [] {
    const CpuFeatures& f = cpu_features();
    if (f.avx512f) return f.avx512vbmi2 ? LaneIsa::avx512_vbmi2 : LaneIsa::avx512;
    return f.avx2 ? LaneIsa::avx2 : LaneIsa::scalar;
  }();
  if (!lanes_active()) return LaneIsa::scalar;
  return LaneIsa(std::min(int(cpu), g_lane_isa_cap.load(std::memory_order_relaxed)));
}

void cap_lane_isa(LaneIsa widest) { g_lane_isa_cap.store(int(widest), std::memory_order_relaxed); }

void lane_blocks_window(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window) {
  if (b >= e) return;
#if PNB_X86_KERNELS
  switch (lane_isa()) {
    case LaneIsa::avx512_vbmi2: avx512_blocks<FunnelShift>(p, b, e, window); break;
    case LaneIsa::avx512: avx512_blocks<TwoShifts>(p, b, e, window); break;
    case LaneIsa::avx2: lane_blocks_window_avx2(p, b, e, window); break;
    case LaneIsa::scalar: scalar_window(p, b, e, window); return;  // raw lanes included
  }
  write_raw_lanes(p, b, e, window);
#else
  scalar_window(p, b, e, window);  // raw lanes included
#endif
}

void lane_blocks_next(const EncodedPage& p, std::uint64_t b, std::uint64_t e, LaneBlockState* states, float* out) {
  const LaneIsa isa = b < e && states[b].t > 0 ? lane_isa() : LaneIsa::scalar;
  if (isa == LaneIsa::scalar) {
    for (std::uint64_t k = b; k < e; ++k) {
      lane_block_step(p, k, states[k]);
      lane_block_write(p, k, states[k], out + k * kLaneBlock);
    }
    return;
  }
#if PNB_X86_KERNELS
  if (isa == LaneIsa::avx512_vbmi2)
    avx512_next<FunnelShift>(p, b, e, states, out);
  else if (isa == LaneIsa::avx512)
    avx512_next<TwoShifts>(p, b, e, states, out);
  else
    lane_blocks_next_avx2(p, b, e, states, out);
  for (std::uint64_t k = b; k < e; ++k)
    if (p.lanes.raw[k]) write_raw_step(p, k, states[k].t - 1, out + k * kLaneBlock);
#endif
}

void lane_blocks_step(const EncodedPage& p, std::uint32_t t, std::uint64_t b, std::uint64_t e, float* out,
                      LaneBlockState* states) {
  LaneBlockState local;
  for (std::uint64_t k = b; k < e; ++k) {
    LaneBlockState& s = states ? states[k - b] : local;
    lane_block_begin(p, k, s);
    for (std::uint32_t i = 0; i <= t; ++i) lane_block_step(p, k, s);
    lane_block_write(p, k, s, out + k * kLaneBlock);
  }
}

void lane_blocks_vertex(const EncodedPage& p, std::uint64_t v, float* out) {
  const std::uint64_t b = v / kLaneBlock;
  LaneBlockState s;
  float row[kLaneBlock];
  lane_block_begin(p, b, s);
  for (std::uint32_t t = 0; t < p.step_count; ++t) {
    lane_block_step(p, b, s);
    lane_block_write(p, b, s, row);
    out[t] = row[v % kLaneBlock];
  }
}

}  // namespace penumbra::compression::detail
