// SPDX-License-Identifier: BSD-3-Clause
// compression/src/lane_blocks_avx2.cpp -- the AVX2 decoders of predictive_lanes pages, for CPUs
// without AVX-512: each block of 16 lanes as two vectors of 8, bit-identical to lane_block_step.
// Empty in a build without x86 kernels (cpu_features.h).
#include "cpu_features.h"

#if PNB_X86_KERNELS
#include <immintrin.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <type_traits>

#include "lane_blocks.h"
#include "target_region.h"

namespace penumbra::compression::detail {

namespace {

PNB_TARGET_REGION_BEGIN("avx2")

constexpr std::uint64_t kHalf = kLaneBlock / 2;

// One block's 32 bits of every column that end at bit `end`, as lanes 0-7 and 8-15: from the row
// `end` lies in and the row below it (the page's zero row below row 0), as the AVX-512 decoder
// reads them. A slot that ends there is their top bits.
inline void bits_ending256(const std::uint32_t* rows, std::uint64_t end, __m256i u[2]) {
  const std::uint32_t* r = row_holding(rows, end);
  const __m128i right = _mm_cvtsi32_si128(int(end & 31)), left = _mm_cvtsi32_si128(int(32 - (end & 31)));
  for (std::uint64_t h = 0; h < 2; ++h) {
    const __m256i below = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(r - kLaneBlock + h * kHalf));
    const __m256i at = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(r + h * kHalf));
    u[h] = _mm256_or_si256(_mm256_srl_epi32(below, right), _mm256_sll_epi32(at, left));
  }
}

// The unsigned `width`-bit slots at bit `pos` (k_0; width 0: a shift by 32, zeros), moving pos on.
inline void unsigned_slots256(const std::uint32_t* rows, std::uint64_t& pos, std::uint32_t width, __m256i u[2]) {
  const __m128i spare = _mm_cvtsi32_si128(int(32 - width));
  pos += width;
  bits_ending256(rows, pos, u);
  for (std::uint64_t h = 0; h < 2; ++h) u[h] = _mm256_srl_epi32(u[h], spare);
}

// The two's-complement `width`-bit slots at bit `pos`, sign-extended by the one shift that
// extracts them, moving pos on.
inline void signed_slots256(const std::uint32_t* rows, std::uint64_t& pos, std::uint32_t width, __m256i u[2]) {
  if (width == 0) {
    u[0] = u[1] = _mm256_setzero_si256();
    return;
  }
  const __m128i spare = _mm_cvtsi32_si128(int(32 - width));
  pos += width;
  bits_ending256(rows, pos, u);
  for (std::uint64_t h = 0; h < 2; ++h) u[h] = _mm256_sra_epi32(u[h], spare);
}

// Adds exception row `row`'s high parts to its lanes of u, moving row and high on (rare: lane by
// lane through memory).
inline void patch256(const LaneBlocks& L, std::uint64_t& row, std::uint64_t& high, std::uint32_t width, __m256i u[2]) {
  alignas(32) std::uint32_t lanes[kLaneBlock];
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), u[0]);
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes + kHalf), u[1]);
  for (std::uint32_t m = L.exception_lanes[row++]; m; m &= m - 1)
    lanes[std::countr_zero(m)] += std::uint32_t(std::uint64_t(L.highs[high++]) << width);
  u[0] = _mm256_load_si256(reinterpret_cast<const __m256i*>(lanes));
  u[1] = _mm256_load_si256(reinterpret_cast<const __m256i*>(lanes + kHalf));
}

// All ones in the lanes of `bits` (bit l: lane l) among lanes 8 h .. 8 h + 7.
inline __m256i lane_mask(std::uint32_t bits, std::uint64_t h) {
  const __m256i select = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const __m256i b = _mm256_and_si256(_mm256_set1_epi32(int(bits >> (8 * h))), select);
  return _mm256_cmpeq_epi32(b, select);
}

// Stores a block's values: whole vectors, or the first `lanes` of them (the last block).
inline void put256(const __m256 v[2], std::uint64_t lanes, float* out) {
  if (lanes == kLaneBlock) {
    _mm256_storeu_ps(out, v[0]);
    _mm256_storeu_ps(out + kHalf, v[1]);
    return;
  }
  alignas(32) float all[kLaneBlock];
  _mm256_store_ps(all, v[0]);
  _mm256_store_ps(all + kHalf, v[1]);
  std::memcpy(out, all, lanes * 4);
}

// A window above this (about half of L2) gets row prefetches: see lane_blocks_window_avx2.
constexpr std::uint64_t kPrefetchWindowBytes = 1 << 20;

// Each block keeps k and its last difference as in avx512_window. One block at a time: its two
// halves' chains overlap enough, and two blocks' state no longer fits in the 16 vector registers
// (they spilled, and decoded mug 25 % slower).
template <bool kPrefetch>
void avx2_window_impl(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window) {
  const LaneBlocks& L = p.lanes;
  const std::uint64_t N = p.vertex_count;
  const std::uint32_t n = p.step_count, fw = p.quantiser.first_width;
  const std::uint32_t* rows = lane_rows(L);
  const std::uint16_t* exception_steps = L.exception_steps.data();
  const __m256 lo = _mm256_set1_ps(p.quantiser.lo), step = _mm256_set1_ps(p.quantiser.step);
  for (std::uint64_t c = b; c < e; ++c) {
    const std::uint64_t lanes = lane_block_lanes(N, c), row_end = L.row_start[c + 1];
    const std::uint32_t w1 = lane_width_1(L, c);
    const __m256i linear[2] = {lane_mask(L.linear[c], 0), lane_mask(L.linear[c], 1)};
    std::uint64_t pos = L.bit_start[c], row = L.row_start[c], high = L.high_start[c];
    std::uint32_t next = next_exception_step(exception_steps, row, row_end);
    __m256i k[2], d[2] = {_mm256_setzero_si256(), _mm256_setzero_si256()};  // d: only read after step 1 sets it
    // The prediction errors at step t, with the block's exception row's high parts if it has one.
    const auto errors = [&](std::uint32_t t, std::uint32_t width, __m256i u[2]) {
      signed_slots256(rows, pos, width, u);
      if (next == t) {
        patch256(L, row, high, width, u);
        next = next_exception_step(exception_steps, row, row_end);
      }
    };
    const auto put = [&](float* row_out) {
      const __m256 v[2] = {_mm256_add_ps(lo, _mm256_mul_ps(_mm256_cvtepi32_ps(k[0]), step)),
                           _mm256_add_ps(lo, _mm256_mul_ps(_mm256_cvtepi32_ps(k[1]), step))};
      put256(v, lanes, row_out);
      if constexpr (kPrefetch) prefetch_row_ahead(row_out);
    };
    float* out = window + c * kLaneBlock;
    unsigned_slots256(rows, pos, fw, k);
    put(out);
    if (n >= 2) {
      out += N;
      errors(1, w1, d);
      for (std::uint64_t h = 0; h < 2; ++h) k[h] = _mm256_add_epi32(k[h], d[h]);
      put(out);
    }
    // Step 2, the transient steps, then the later ones: one width each; as in avx512_window,
    // loops that do not look for exception rows where none is left.
    const auto steps = [&](const LaneStepSpan& span, auto rows_left) {
      const std::uint32_t w = span.width;
      for (std::uint32_t t = span.from; t < span.to; ++t) {
        out += N;
        __m256i error[2];
        if constexpr (decltype(rows_left)::value)
          errors(t, w, error);
        else
          signed_slots256(rows, pos, w, error);
        for (std::uint64_t h = 0; h < 2; ++h) {
          d[h] = _mm256_add_epi32(error[h], _mm256_and_si256(d[h], linear[h]));
          k[h] = _mm256_add_epi32(k[h], d[h]);
        }
        put(out);
      }
    };
    const auto spans = lane_step_spans(L, c, n);  // named calls: a loop over the spans cost AVX2 7 %
    const auto run = [&](auto rows_left) {
      steps(spans[0], rows_left);
      steps(spans[1], rows_left);
      steps(spans[2], rows_left);
    };
    next == 0 ? run(std::false_type{}) : run(std::true_type{});
  }
}

void avx2_next_impl(const EncodedPage& p, std::uint64_t b, std::uint64_t e, LaneBlockState* states, float* out) {
  const LaneBlocks& L = p.lanes;
  const std::uint32_t* rows = lane_rows(L);
  const __m256 lo = _mm256_set1_ps(p.quantiser.lo), step = _mm256_set1_ps(p.quantiser.step);
  for (std::uint64_t k = b; k < e; ++k) {
    LaneBlockState& s = states[k];
    const std::uint32_t t = s.t, width = lane_step_width(L, k, t);
    __m256i u[2];
    signed_slots256(rows, s.pos, width, u);
    if (exception_row_due(L, k, s)) patch256(L, s.row, s.high, width, u);
    const std::uint32_t linear = t >= 2 ? L.linear[k] : 0;
    __m256 v[2];
    for (std::uint64_t h = 0; h < 2; ++h) {
      __m256i* k1 = reinterpret_cast<__m256i*>(s.k1 + h * kHalf);
      __m256i* k2 = reinterpret_cast<__m256i*>(s.k2 + h * kHalf);
      const __m256i last = _mm256_loadu_si256(k1), before = _mm256_loadu_si256(k2);
      const __m256i trend = _mm256_and_si256(_mm256_sub_epi32(last, before), lane_mask(linear, h));
      const __m256i next = _mm256_add_epi32(_mm256_add_epi32(last, trend), u[h]);
      _mm256_storeu_si256(k2, last);
      _mm256_storeu_si256(k1, next);
      v[h] = _mm256_add_ps(lo, _mm256_mul_ps(_mm256_cvtepi32_ps(next), step));
    }
    ++s.t;
    put256(v, lane_block_lanes(p.vertex_count, k), out + k * kLaneBlock);
  }
}

PNB_TARGET_REGION_END

}  // namespace

void lane_blocks_window_avx2(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window) {
  // Row prefetches (prefetch_row_ahead) only for a window that outgrows L2: 1.46x on 100K vertices
  // at 1e-3, but 0.86-0.93x on mug's 317 KB, held in cache, where this kernel is bound by its
  // instructions (measured with this decoder forced on an AVX-512 core).
  if (p.vertex_count * p.step_count * sizeof(float) > kPrefetchWindowBytes)
    avx2_window_impl<true>(p, b, e, window);
  else
    avx2_window_impl<false>(p, b, e, window);
}

void lane_blocks_next_avx2(const EncodedPage& p, std::uint64_t b, std::uint64_t e, LaneBlockState* states, float* out) {
  avx2_next_impl(p, b, e, states, out);
}

}  // namespace penumbra::compression::detail

#endif  // PNB_X86_KERNELS
