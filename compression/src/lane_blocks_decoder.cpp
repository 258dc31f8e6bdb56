// compression/src/lane_blocks_decoder.cpp -- decoders of predictive_lanes pages: a scalar one
// that every path can use, and an AVX-512 whole-window decoder that is bit-identical to it.
#include <immintrin.h>

#include <algorithm>
#include <bit>

#include "lane_blocks.h"
#include "section_lanes.h"

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
  const std::uint32_t* words = L.words.data();
  const std::uint32_t t = s.t;
  if (t == 0) {
    for (std::uint32_t l = 0; l < kLaneBlock; ++l) s.k1[l] = s.k2[l] = lane_slot(words, s.pos, l, p.first_width);
    s.pos += p.first_width;
    s.t = 1;
    return;
  }
  const std::uint32_t width = t == 1 ? lane_width_1(L, b) : lane_width(L, b);
  std::uint32_t u[kLaneBlock];
  for (std::uint32_t l = 0; l < kLaneBlock; ++l) u[l] = lane_slot(words, s.pos, l, width);
  if (s.row < L.row_start[b + 1] && L.exception_steps[s.row] == t) {
    for (std::uint32_t lanes = L.exception_lanes[s.row++]; lanes; lanes &= lanes - 1)
      u[std::countr_zero(lanes)] += std::uint32_t(std::uint64_t(L.highs[s.high++]) << width);
  }
  const std::uint32_t bias = offset_bias(width);
  const std::uint16_t linear = t >= 2 ? L.linear[b] : 0;
  for (std::uint32_t l = 0; l < kLaneBlock; ++l) {
    const std::uint32_t prediction = (linear >> l & 1) ? 2u * s.k1[l] - s.k2[l] : s.k1[l];
    s.k2[l] = s.k1[l];
    s.k1[l] = prediction + (u[l] - bias);
  }
  s.pos += width;
  ++s.t;
}

void lane_block_write(const EncodedPage& p, std::uint64_t b, const LaneBlockState& s, float* row) {
  const LaneBlocks& L = p.lanes;
  const std::uint64_t lanes = std::min<std::uint64_t>(kLaneBlock, p.vertex_count - b * kLaneBlock);
  for (std::uint64_t l = 0; l < lanes; ++l) row[l] = p.lo + float(std::int32_t(s.k1[l])) * p.step;
  const std::uint32_t t = s.t - 1, n = p.step_count;
  const float* raw = L.raw_values.data() + L.raw_start[b];
  for (std::uint32_t m = L.raw[b]; m; m &= m - 1, raw += n) row[std::countr_zero(m)] = raw[t];
}

namespace {

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

bool avx512_active() {
  static const bool cpu = __builtin_cpu_supports("avx512f");
  return cpu && lanes_active();
}

// GCC 12 warns that the AVX-512 intrinsics' own undefined-vector placeholders may be used
// uninitialised (a false positive inside immintrin.h).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// A target region rather than an attribute, so that the lambdas inside are compiled for it too.
#pragma GCC push_options
#pragma GCC target("avx512f")
// Four blocks side by side, so that their prediction chains overlap. Each step of a block is two
// row loads, a shift of each and a mask; an exception row adds its high parts, expanded into their
// lanes. Bit-identical to lane_block_step: the same wrapping integers, then a multiply and an add
// that are never fused.
void avx512_window(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window) {
  constexpr std::uint64_t kBlocks = 4;
  const LaneBlocks& L = p.lanes;
  const std::uint64_t N = p.vertex_count;
  const std::uint32_t n = p.step_count, fw = p.first_width;
  const std::uint32_t* words = L.words.data();
  const std::uint32_t* highs = L.highs.data();
  const __m512 lo = _mm512_set1_ps(p.lo), step = _mm512_set1_ps(p.step);
  const std::uint64_t tail = N - (lane_block_count(N) - 1) * kLaneBlock;
  const __mmask16 last_lanes = __mmask16(tail == kLaneBlock ? 0xFFFF : (1u << tail) - 1);
  for (std::uint64_t b0 = b; b0 < e; b0 += kBlocks) {
    // A short group repeats its last block in the spare slots and stores none of them.
    __m512i k1[kBlocks], k2[kBlocks];
    __mmask16 linear[kBlocks], store[kBlocks];
    std::uint64_t pos[kBlocks];
    std::uint32_t w1[kBlocks], w[kBlocks], row[kBlocks], row_end[kBlocks], next[kBlocks], high[kBlocks];
    for (std::uint64_t j = 0; j < kBlocks; ++j) {
      const std::uint64_t k = std::min(b0 + j, e - 1);
      store[j] = b0 + j >= e ? 0 : k + 1 == lane_block_count(N) ? last_lanes : 0xFFFF;
      linear[j] = L.linear[k];
      pos[j] = L.bit_start[k];
      w1[j] = lane_width_1(L, k);
      w[j] = lane_width(L, k);
      row[j] = L.row_start[k];
      row_end[j] = L.row_start[k + 1];
      next[j] = row[j] < row_end[j] ? L.exception_steps[row[j]] : 0;
      high[j] = L.high_start[k];
    }
    // One step of block j at `width` bits: the two rows its slots lie in, shifted together.
    const auto slots = [&](std::uint64_t j, std::uint32_t width) {
      const std::uint32_t* r = words + (pos[j] >> 5) * kLaneBlock;
      const std::uint32_t sh = std::uint32_t(pos[j] & 31);
      pos[j] += width;
      return _mm512_or_si512(_mm512_srl_epi32(_mm512_loadu_si512(r), _mm_cvtsi32_si128(int(sh))),
                             _mm512_sll_epi32(_mm512_loadu_si512(r + kLaneBlock), _mm_cvtsi32_si128(int(32 - sh))));
    };
    // Adds the high parts of block j's exception row at step t, if it has one.
    const auto patch = [&](std::uint64_t j, std::uint32_t t, std::uint32_t width, __m512i u) {
      if (next[j] != t) return u;
      const __mmask16 lanes = L.exception_lanes[row[j]];
      const __m512i h = _mm512_maskz_expandloadu_epi32(lanes, highs + high[j]);
      high[j] += std::uint32_t(std::popcount(std::uint32_t(lanes)));
      ++row[j];
      next[j] = row[j] < row_end[j] ? L.exception_steps[row[j]] : 0;
      return _mm512_add_epi32(u, _mm512_sll_epi32(h, _mm_cvtsi32_si128(int(width))));
    };
    const auto put = [&](float* out, std::uint64_t j) {
      _mm512_mask_storeu_ps(out + j * kLaneBlock, store[j], _mm512_add_ps(lo, _mm512_mul_ps(_mm512_cvtepi32_ps(k1[j]), step)));
    };
    float* out = window + b0 * kLaneBlock;
    for (std::uint64_t j = 0; j < kBlocks; ++j) {
      k1[j] = k2[j] = _mm512_and_si512(slots(j, fw), _mm512_set1_epi32(int(low_mask(fw))));
      put(out, j);
    }
    if (n >= 2) {
      out += N;
      for (std::uint64_t j = 0; j < kBlocks; ++j) {
        __m512i u = _mm512_and_si512(slots(j, w1[j]), _mm512_set1_epi32(int(low_mask(w1[j]))));
        u = patch(j, 1, w1[j], u);
        k1[j] = _mm512_add_epi32(k1[j], _mm512_sub_epi32(u, _mm512_set1_epi32(int(offset_bias(w1[j])))));
        put(out, j);
      }
    }
    __m512i mask[kBlocks], bias[kBlocks];
    for (std::uint64_t j = 0; j < kBlocks; ++j) {
      mask[j] = _mm512_set1_epi32(int(low_mask(w[j])));
      bias[j] = _mm512_set1_epi32(int(offset_bias(w[j])));
    }
    for (std::uint32_t t = 2; t < n; ++t) {
      out += N;
      for (std::uint64_t j = 0; j < kBlocks; ++j) {
        __m512i u = _mm512_and_si512(slots(j, w[j]), mask[j]);
        u = patch(j, t, w[j], u);
        const __m512i prediction = _mm512_mask_add_epi32(k1[j], linear[j], k1[j], _mm512_sub_epi32(k1[j], k2[j]));
        k2[j] = k1[j];
        k1[j] = _mm512_add_epi32(prediction, _mm512_sub_epi32(u, bias[j]));
        put(out, j);
      }
    }
  }
  write_raw_lanes(p, b, e, window);
}
#pragma GCC pop_options
#pragma GCC diagnostic pop

}  // namespace

void lane_blocks_window(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window) {
  if (b >= e) return;
  if (avx512_active())
    avx512_window(p, b, e, window);
  else
    scalar_window(p, b, e, window);
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
