// SPDX-License-Identifier: BSD-3-Clause
// compression/src/vq_lanes.cpp
#include "vq_lanes.h"

#include <algorithm>
#include <vector>

#include "cpu_features.h"
#include "lane_blocks.h"
#include "lane_ops.h"
#include "section_lanes.h"
#include "vq_value.h"

namespace penumbra::compression::detail {

namespace {

// The whole lane blocks of [0, count); the caller finishes the rest with scalar code (all of it
// in a build without x86 kernels, where the lane branches below are compiled out).
std::uint64_t lane_part(std::uint64_t count) { return lanes_active() ? count / kLanes * kLanes : 0; }

#if PNB_X86_KERNELS
PNB_LANES __m256 means8(__m256 lo, __m256 scale, const std::uint16_t* q) {
  return _mm256_add_ps(lo, _mm256_mul_ps(_mm256_cvtepi32_ps(widen16(q)), scale));
}

PNB_LANES __m256 lookup(const float* table, __m256i index) { return _mm256_i32gather_ps(table, index, 4); }

// Row indices times the row length: D8 rows are 8 floats (a shift), D_W rows `stride`.
PNB_LANES __m256i rows8(const std::uint8_t* index) { return _mm256_slli_epi32(widen8(index), 3); }
PNB_LANES __m256i rows(const std::uint8_t* index, __m256i stride) { return _mm256_mullo_epi32(widen8(index), stride); }

__attribute__((target("avx2"))) void add_entries_lanes(const float* table, std::int32_t stride,
                                                       const std::uint8_t* index, const float* base,
                                                       std::uint64_t count, float* out) {
  const __m256i d = _mm256_set1_epi32(stride);
  for (std::uint64_t i = 0; i < count; i += kLanes)
    store(out + i, _mm256_add_ps(load(base + i), lookup(table, rows(index + i, d))));
}

// 8 x 8 transpose: r[l] holds row l's eight values; c[k] gets value k of rows 0..7.
PNB_LANES void transpose8(const __m256 r[8], __m256 c[8]) {
  __m256 t[8], q[8];
  for (int l = 0; l < 8; l += 2) {
    t[l] = _mm256_unpacklo_ps(r[l], r[l + 1]);
    t[l + 1] = _mm256_unpackhi_ps(r[l], r[l + 1]);
  }
  for (int h = 0; h < 8; h += 4) {
    q[h] = _mm256_shuffle_ps(t[h], t[h + 2], _MM_SHUFFLE(1, 0, 1, 0));
    q[h + 1] = _mm256_shuffle_ps(t[h], t[h + 2], _MM_SHUFFLE(3, 2, 3, 2));
    q[h + 2] = _mm256_shuffle_ps(t[h + 1], t[h + 3], _MM_SHUFFLE(1, 0, 1, 0));
    q[h + 3] = _mm256_shuffle_ps(t[h + 1], t[h + 3], _MM_SHUFFLE(3, 2, 3, 2));
  }
  for (int k = 0; k < 4; ++k) {
    c[k] = _mm256_permute2f128_ps(q[k], q[k + 4], 0x20);
    c[k + 4] = _mm256_permute2f128_ps(q[k], q[k + 4], 0x31);
  }
}

// The eight values from table + row[l] of 8 rows, transposed: c[k] = table[row[l] + k], l < 8.
PNB_LANES void rows_transposed(const float* table, const std::int32_t* row, __m256 c[8]) {
  __m256 r[8];
  for (int l = 0; l < 8; ++l) r[l] = _mm256_loadu_ps(table + row[l]);
  transpose8(r, c);
}

__attribute__((target("avx2"))) void add_rows8_lanes(const float* table, const std::int32_t* row, const float* base,
                                                     std::uint64_t count, float* out, std::uint64_t stride,
                                                     std::uint32_t steps) {
  for (std::uint64_t i = 0; i < count; i += kLanes) {
    __m256 c[8];
    rows_transposed(table, row + i, c);
    const __m256 b = load(base + i);
    for (std::uint32_t k = 0; k < steps; ++k) store(out + std::uint64_t(k) * stride + i, _mm256_add_ps(b, c[k]));
  }
}

// Where each vertex of a run's rows start: row8[j] in the D8 codebook, roww[j] in the D_W one;
// `run` a multiple of 8. In lanes: GCC left the scalar loop as it was, about 10 instructions a
// vertex (this form: 1.02x on mug's plain-VQ pages).
PNB_LANES void run_rows(const std::uint8_t* i8, const std::uint8_t* iw, std::uint32_t window, std::uint64_t run,
                        std::int32_t* row8, std::int32_t* roww) {
  const __m256i w = _mm256_set1_epi32(std::int32_t(window));
  for (std::uint64_t j = 0; j < run; j += kLanes) {
    store(row8 + j, rows8(i8 + j));
    store(roww + j, _mm256_mullo_epi32(widen8(iw + j), w));
  }
}

// mean + D8 of 8 vertices (mean_q and row8 at the first) for each D8 block k < blocks, into
// base[k * run_capacity].
PNB_LANES void means_plus_d8(__m256 lo, __m256 scale, const std::uint16_t* mean_q, const float* c8,
                             const std::int32_t* row8, std::uint32_t blocks, float* base, std::uint64_t run_capacity) {
  __m256 d8[8];
  rows_transposed(c8, row8, d8);
  const __m256 mean = means8(lo, scale, mean_q);
  for (std::uint32_t k = 0; k < blocks; ++k) _mm256_store_ps(base + std::uint64_t(k) * run_capacity, _mm256_add_ps(mean, d8[k]));
}

// Steps t .. t + k_end - 1 of 8 vertices: base b plus their D_W values (table at step t, rows
// row), plus the residual of lanes `lane` .. lane + 7 where they have one; written at `at`, a step
// `stride` apart. Lanes without a residual keep the VQ value as it is (code 0 keeps -0.0f, as in
// the scalar decoders); vertices without one (most, on sparse residuals) store it directly.
template <bool kWithResidual>
PNB_LANES void steps8(const float* table, const std::int32_t* row, const float* b, float* at, std::uint64_t stride,
                      std::uint32_t t, std::uint32_t k_end, const ResidualLanes* residual, std::uint64_t lane) {
  __m256 c[8];
  rows_transposed(table, row, c);
  const __m256 bj = _mm256_load_ps(b);
  const __m256 adds = kWithResidual ? _mm256_castsi256_ps(load(residual->adds + lane)) : _mm256_setzero_ps();
  const int adding = kWithResidual ? _mm256_movemask_ps(adds) : 0;
  if (adding) {
    const __m256 step = _mm256_set1_ps(residual->step);
    const std::uint32_t* z = residual->z + std::uint64_t(t) * kResidualStride + lane;
    for (std::uint32_t k = 0; k < k_end; ++k, z += kResidualStride) {
      const __m256 value = _mm256_add_ps(bj, c[k]);
      const __m256 sum = add_scaled(value, unzigzag_lanes(load(z)), step);
      store(at + std::uint64_t(k) * stride, adding == 0xFF ? sum : _mm256_blendv_ps(value, sum, adds));
    }
  } else {
    for (std::uint32_t k = 0; k < k_end; ++k) store(at + std::uint64_t(k) * stride, _mm256_add_ps(bj, c[k]));
  }
}

template <bool kWithResidual>
__attribute__((target("avx2"))) void vq_window_lanes(float lo, float scale, const std::uint16_t* mean_q,
                                                     const float* c8, const std::uint8_t* i8, const float* cw,
                                                     std::uint32_t window, const std::uint8_t* iw,
                                                     std::uint64_t count, float* out, std::uint64_t stride,
                                                     std::uint32_t steps, const ResidualLanes* residual) {
  // Vertices in runs of kRun: first mean + D8 of every block of steps for the run (each vertex's
  // D8 row is one read of 8 floats, transposed), then the steps eight at a time, each writing
  // eight step rows of the run. Going through all steps of 8 vertices at once instead touched
  // one page per step row for every 32 bytes written (a third slower on 100K vertices).
  constexpr std::uint64_t kRun = 256;
  const __m256 l = _mm256_set1_ps(lo), s = _mm256_set1_ps(scale);
  const std::uint32_t block = window / 8, blocks = (steps + block - 1) / block;  // the D8 blocks the steps reach
  alignas(32) float base[8 * kRun];
  alignas(32) std::int32_t row8[kRun], roww[kRun];
  for (std::uint64_t r0 = 0; r0 < count; r0 += kRun) {
    const std::uint64_t run = std::min(kRun, count - r0);  // a multiple of 8
    run_rows(i8 + r0, iw + r0, window, run, row8, roww);
    for (std::uint64_t j = 0; j < run; j += kLanes)
      means_plus_d8(l, s, mean_q + r0 + j, c8, row8 + j, blocks, base + j, kRun);
    for (std::uint32_t t = 0; t < steps; t += 8) {
      const float* b = base + std::uint64_t(t / block) * kRun;
      const std::uint32_t k_end = std::min<std::uint32_t>(8, steps - t);
      float* at = out + std::uint64_t(t) * stride + r0;
      for (std::uint64_t j = 0; j < run; j += kLanes)
        steps8<kWithResidual>(cw + t, roww + j, b + j, at + j, stride, t, k_end, residual, r0 + j);
    }
  }
}

// GCC 12 warns that the AVX-512 intrinsics' own undefined-vector placeholders may be used
// uninitialised (a false positive inside immintrin.h).
#pragma GCC diagnostic push
#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
// The AVX-512 transpose of 16 rows of 8: r[l] holds row l in its low half and row l + 8 in its
// high half; c[k] gets value k of rows 0..15. transpose8's steps run on both halves at once (the
// unpacks and shuffles work within 128-bit lanes), and the last one joins lanes of a half with a
// two-source permute.
__attribute__((target("avx512f"), always_inline)) inline void transpose16x8(const __m512 r[8], __m512 c[8]) {
  __m512 t[8], q[8];
  for (int l = 0; l < 8; l += 2) {
    t[l] = _mm512_unpacklo_ps(r[l], r[l + 1]);
    t[l + 1] = _mm512_unpackhi_ps(r[l], r[l + 1]);
  }
  for (int h = 0; h < 8; h += 4) {
    q[h] = _mm512_shuffle_ps(t[h], t[h + 2], _MM_SHUFFLE(1, 0, 1, 0));
    q[h + 1] = _mm512_shuffle_ps(t[h], t[h + 2], _MM_SHUFFLE(3, 2, 3, 2));
    q[h + 2] = _mm512_shuffle_ps(t[h + 1], t[h + 3], _MM_SHUFFLE(1, 0, 1, 0));
    q[h + 3] = _mm512_shuffle_ps(t[h + 1], t[h + 3], _MM_SHUFFLE(3, 2, 3, 2));
  }
  // Per 256-bit half, permute2f128's 0x20 (both low 128-bit lanes) and 0x31 (both high ones).
  const __m512i low = _mm512_setr_epi32(0, 1, 2, 3, 16, 17, 18, 19, 8, 9, 10, 11, 24, 25, 26, 27);
  const __m512i high = _mm512_setr_epi32(4, 5, 6, 7, 20, 21, 22, 23, 12, 13, 14, 15, 28, 29, 30, 31);
  for (int k = 0; k < 4; ++k) {
    c[k] = _mm512_permutex2var_ps(q[k], low, q[k + 4]);
    c[k + 4] = _mm512_permutex2var_ps(q[k], high, q[k + 4]);
  }
}

// The eight floats at table + row[l] of 16 rows, transposed: c[k] = table[row[l] + k], l < 16.
// Rows l and l + 8 share a register (low and high halves).
__attribute__((target("avx512f"), always_inline)) inline void rows_transposed16(const float* table,
                                                                                 const std::int32_t* row, __m512 c[8]) {
  __m512 r[8];
  for (int v = 0; v < 8; ++v)
    r[v] = _mm512_castpd_ps(_mm512_insertf64x4(_mm512_castps_pd(_mm512_castps256_ps512(_mm256_loadu_ps(table + row[v]))),
                                               _mm256_castps_pd(_mm256_loadu_ps(table + row[8 + v])), 1));
  transpose16x8(r, c);
}

// Rows of a window rarely start on a cache line (a row is vertex_count floats), and a 64-byte
// store across two lines cost a third more time than one within a line on mug's page, held in
// cache. So each row's stores cover exactly one line: lane l of the store at vertex j - m is the
// previous group's lane 16 - m + l while l < m, else this group's lane l - m, where m is how far
// the row's vertex j sits into its line. A row's first and last lines are masked stores.
struct LineAlignedRow {
  float* line;   // where the group at vertex j stores: the row at vertex j - m
  __m512i pick;  // 16 - m + l: the two-source permute that joins two groups
  unsigned m;    // floats from the line's start to vertex j
};

__attribute__((target("avx512f"), always_inline)) inline LineAlignedRow line_aligned_row(float* row) {
  const std::uintptr_t at = reinterpret_cast<std::uintptr_t>(row);
  const unsigned m = unsigned(at / sizeof(float)) & 15u;
  return {reinterpret_cast<float*>(at - m * sizeof(float)),
          _mm512_add_epi32(_mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15),
                           _mm512_set1_epi32(int(16 - m))),
          m};
}

// Steps t .. t + K - 1 of a run's 16-vertex groups [0, groups * 16): each vertex's mean plus its
// D8 value (gathered from `d8`, the column of D8 block t / block, at row8), plus its D_W values
// (rows `row` of `table`, the D_W codebook at step t); output rows stride apart from `at` (the
// run's first vertex at step t). One transpose per group; its K sums are joined with the previous
// group's into line-aligned stores. The last group's sums wait in `carry` (16 floats a row) for
// the next run's first store; the first run of a call masks its first lines, and the last run
// with whole groups stores the last, partial ones. Without kJoin every row starts on a line
// (m = 0: an aligned output and a vertex count that is a multiple of 16), and the sums are
// stored as they are.
template <int K, bool kJoin>
__attribute__((target("avx512f"), always_inline)) inline void steps16_run(const float* table, const std::int32_t* row,
                                                                          const float* mean, const float* d8,
                                                                          const std::int32_t* row8, float* at,
                                                                          std::uint64_t stride, std::uint64_t groups,
                                                                          float* carry, bool first, bool last) {
  LineAlignedRow r[K];
  for (int k = 0; k < K; ++k) r[k] = line_aligned_row(at + std::uint64_t(k) * stride);
  __m512 prev[K];
  {
    __m512 c[8];
    rows_transposed16(table, row, c);
    const __m512 bj = _mm512_add_ps(_mm512_load_ps(mean), _mm512_i32gather_ps(_mm512_load_si512(row8), d8, 4));
    for (int k = 0; k < K; ++k) {
      prev[k] = _mm512_add_ps(bj, c[k]);
      if (!kJoin)
        _mm512_store_ps(r[k].line, prev[k]);
      else if (first)
        _mm512_mask_storeu_ps(r[k].line, __mmask16(0xFFFFu << r[k].m), _mm512_permutex2var_ps(prev[k], r[k].pick, prev[k]));
      else
        _mm512_storeu_ps(r[k].line, _mm512_permutex2var_ps(_mm512_load_ps(carry + 16 * k), r[k].pick, prev[k]));
    }
  }
  for (std::uint64_t g = 1; g < groups; ++g) {
    __m512 c[8];
    rows_transposed16(table, row + 16 * g, c);
    const __m512 bj = _mm512_add_ps(_mm512_load_ps(mean + 16 * g),
                                    _mm512_i32gather_ps(_mm512_load_si512(row8 + 16 * g), d8, 4));
    for (int k = 0; k < K; ++k) {
      const __m512 sum = _mm512_add_ps(bj, c[k]);
      _mm512_store_ps(r[k].line + 16 * g, kJoin ? _mm512_permutex2var_ps(prev[k], r[k].pick, sum) : sum);
      prev[k] = sum;
    }
  }
  if (!kJoin) return;
  if (last) {
    for (int k = 0; k < K; ++k)
      _mm512_mask_storeu_ps(r[k].line + 16 * groups, __mmask16((1u << r[k].m) - 1u),
                            _mm512_permutex2var_ps(prev[k], r[k].pick, prev[k]));
  } else {
    for (int k = 0; k < K; ++k) _mm512_store_ps(carry + 16 * k, prev[k]);
  }
}

template <bool kJoin>
__attribute__((target("avx512f"), always_inline)) inline void steps16_runs(std::uint32_t k, const float* table,
                                                                           const std::int32_t* row, const float* mean,
                                                                           const float* d8, const std::int32_t* row8,
                                                                           float* at, std::uint64_t stride,
                                                                           std::uint64_t groups, float* carry,
                                                                           bool first, bool last) {
  switch (k) {
    case 1: return steps16_run<1, kJoin>(table, row, mean, d8, row8, at, stride, groups, carry, first, last);
    case 2: return steps16_run<2, kJoin>(table, row, mean, d8, row8, at, stride, groups, carry, first, last);
    case 3: return steps16_run<3, kJoin>(table, row, mean, d8, row8, at, stride, groups, carry, first, last);
    case 4: return steps16_run<4, kJoin>(table, row, mean, d8, row8, at, stride, groups, carry, first, last);
    case 5: return steps16_run<5, kJoin>(table, row, mean, d8, row8, at, stride, groups, carry, first, last);
    case 6: return steps16_run<6, kJoin>(table, row, mean, d8, row8, at, stride, groups, carry, first, last);
    case 7: return steps16_run<7, kJoin>(table, row, mean, d8, row8, at, stride, groups, carry, first, last);
    default: return steps16_run<8, kJoin>(table, row, mean, d8, row8, at, stride, groups, carry, first, last);
  }
}

// run_rows 16 vertices at a time: 1.04-1.05x on mug's plain-VQ pages, against 1.02x for 8 at a time.
__attribute__((target("avx512f"), always_inline)) inline void run_rows16(const std::uint8_t* i8, const std::uint8_t* iw,
                                                                         std::uint32_t window, std::uint64_t run,
                                                                         std::int32_t* row8, std::int32_t* roww) {
  const __m512i w = _mm512_set1_epi32(std::int32_t(window));
  std::uint64_t j = 0;
  for (; j + 16 <= run; j += 16) {
    const __m512i a = _mm512_cvtepu8_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(i8 + j)));
    const __m512i b = _mm512_cvtepu8_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(iw + j)));
    _mm512_store_si512(row8 + j, _mm512_slli_epi32(a, 3));
    _mm512_store_si512(roww + j, _mm512_mullo_epi32(b, w));
  }
  run_rows(i8 + j, iw + j, window, run - j, row8 + j, roww + j);
}

// vq_window_lanes<false> with 16 vertices at a time: each vertex's runs of eight D_W values are
// still one read each, rows l and l + 8 of a group share a register, and one transpose, eight
// adds and eight line-aligned stores serve 16 vertices where the AVX2 form needs two transposes
// and sixteen stores, most across two lines; mean + D8 is gathered per group and block of steps.
// Runs hold a multiple of 16 vertices but the last; its last 8, if it has an odd number of eights,
// take the AVX2 form, with a table of mean + D8 for the blocks the page's steps reach.
__attribute__((target("avx512f"))) void vq_window_lanes512(float lo, float scale, const std::uint16_t* mean_q,
                                                           const float* c8, const std::uint8_t* i8, const float* cw,
                                                           std::uint32_t window, const std::uint8_t* iw,
                                                           std::uint64_t count, float* out, std::uint64_t stride,
                                                           std::uint32_t steps) {
  constexpr std::uint64_t kRun = 256;
  const __m256 l = _mm256_set1_ps(lo), s = _mm256_set1_ps(scale);
  const __m512 l16 = _mm512_set1_ps(lo), s16 = _mm512_set1_ps(scale);
  const std::uint32_t block = window / 8, blocks = (steps + block - 1) / block;
  // Rows to join: any that does not start on a line.
  const bool join = ((reinterpret_cast<std::uintptr_t>(out) / sizeof(float)) | stride) % 16 != 0;
  alignas(64) float mean[kRun], tail_base[8 * kLanes];
  alignas(64) std::int32_t row8[kRun], roww[kRun];
  // A row's carry between runs: on the stack for windows up to 64 steps.
  constexpr std::uint32_t kStackRows = 64;
  alignas(64) float carry_stack[kStackRows * 16];
  std::vector<float> carry_heap;
  float* carry = carry_stack;
  if (steps > kStackRows) {
    carry_heap.resize(std::uint64_t(steps + 7) / 8 * 8 * 16 + 16);
    carry = reinterpret_cast<float*>((reinterpret_cast<std::uintptr_t>(carry_heap.data()) + 63) & ~std::uintptr_t(63));
  }
  for (std::uint64_t r0 = 0; r0 < count; r0 += kRun) {
    const std::uint64_t run = std::min(kRun, count - r0);  // a multiple of 8
    run_rows16(i8 + r0, iw + r0, window, run, row8, roww);
    const std::uint64_t groups = run / (2 * kLanes);
    for (std::uint64_t j = 0; j < groups * 2 * kLanes; j += 2 * kLanes) {
      const __m512i q = _mm512_cvtepu16_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(mean_q + r0 + j)));
      _mm512_store_ps(mean + j, _mm512_add_ps(l16, _mm512_mul_ps(_mm512_cvtepi32_ps(q), s16)));
    }
    const std::uint64_t tail = groups * 2 * kLanes;  // the run's last 8 vertices, if tail < run
    if (tail < run) means_plus_d8(l, s, mean_q + r0 + tail, c8, row8 + tail, blocks, tail_base, kLanes);
    // The last run may end with 8 vertices for the AVX2 form, or be only those 8.
    const bool first = r0 == 0, last = r0 + run + 2 * kLanes > count;
    for (std::uint32_t t = 0; t < steps; t += 8) {
      const std::uint32_t k_end = std::min<std::uint32_t>(8, steps - t);
      float* at = out + std::uint64_t(t) * stride + r0;
      float* carry_t = carry + std::uint64_t(t) * 16;
      if (groups && join)
        steps16_runs<true>(k_end, cw + t, roww, mean, c8 + t / block, row8, at, stride, groups, carry_t, first, last);
      else if (groups)
        steps16_runs<false>(k_end, cw + t, roww, mean, c8 + t / block, row8, at, stride, groups, carry_t, first, last);
      if (tail < run)
        steps8<false>(cw + t, roww + tail, tail_base + std::uint64_t(t / block) * kLanes, at + tail, stride, t, k_end,
                      nullptr, r0 + tail);
    }
  }
}

#pragma GCC diagnostic pop

__attribute__((target("avx2"))) void add_offsets_lanes(const float* table, const std::int32_t* offset,
                                                       const float* level, std::uint64_t count, float* out) {
  for (std::uint64_t i = 0; i < count; i += kLanes) {
    const __m256i o = load(offset + i);
    store(out + i, _mm256_add_ps(load(level + i), lookup(table, o)));
  }
}

__attribute__((target("avx2"))) void mean_plus_entries_lanes(float lo, float scale, const std::uint16_t* mean_q,
                                                             const float* t8, const std::uint8_t* i8,
                                                             std::uint64_t count, float* out) {
  const __m256 l = _mm256_set1_ps(lo), s = _mm256_set1_ps(scale);
  for (std::uint64_t i = 0; i < count; i += kLanes)
    store(out + i, _mm256_add_ps(means8(l, s, mean_q + i), lookup(t8, rows8(i8 + i))));
}

__attribute__((target("avx2"))) void vq_step_values_lanes(float lo, float scale, const std::uint16_t* mean_q,
                                                          const float* t8, const std::uint8_t* i8, const float* tw,
                                                          std::int32_t stride, const std::uint8_t* iw,
                                                          std::uint64_t count, float* out) {
  const __m256 l = _mm256_set1_ps(lo), s = _mm256_set1_ps(scale);
  const __m256i d = _mm256_set1_epi32(stride);
  for (std::uint64_t i = 0; i < count; i += kLanes) {
    const __m256 base = _mm256_add_ps(means8(l, s, mean_q + i), lookup(t8, rows8(i8 + i)));
    store(out + i, _mm256_add_ps(base, lookup(tw, rows(iw + i, d))));
  }
}

__attribute__((target("avx2"))) void aligned_step_values_lanes(float lo, float scale, const std::uint16_t* mean_q,
                                                               const float* table, const std::uint8_t* ia,
                                                               const std::uint8_t* shift, std::int32_t stride,
                                                               std::uint64_t count, float* out) {
  const __m256 l = _mm256_set1_ps(lo), s = _mm256_set1_ps(scale);
  const __m256i d = _mm256_set1_epi32(stride);
  for (std::uint64_t i = 0; i < count; i += kLanes) {
    const __m256i o = _mm256_sub_epi32(_mm256_mullo_epi32(widen8(ia + i), d), widen8(shift + i));
    store(out + i, _mm256_add_ps(means8(l, s, mean_q + i), lookup(table, o)));
  }
}
#endif  // PNB_X86_KERNELS

}  // namespace

void add_entries(const float* table, std::int32_t stride, const std::uint8_t* index, const float* base,
                 std::uint64_t count, float* out) {
  std::uint64_t i = lane_part(count);
#if PNB_X86_KERNELS
  if (i) add_entries_lanes(table, stride, index, base, i, out);
#endif
  for (; i < count; ++i) out[i] = base[i] + table[std::ptrdiff_t(index[i]) * stride];
}

void add_rows8(const float* table, const std::int32_t* row, const float* base, std::uint64_t count, float* out,
               std::uint64_t stride, std::uint32_t steps) {
  std::uint64_t i = lane_part(count);
#if PNB_X86_KERNELS
  if (i) add_rows8_lanes(table, row, base, i, out, stride, steps);
#endif
  for (; i < count; ++i)
    for (std::uint64_t k = 0; k < steps; ++k) out[k * stride + i] = base[i] + table[row[i] + std::ptrdiff_t(k)];
}

void add_offsets(const float* table, const std::int32_t* offset, const float* level, std::uint64_t count, float* out) {
  std::uint64_t i = lane_part(count);
#if PNB_X86_KERNELS
  if (i) add_offsets_lanes(table, offset, level, i, out);
#endif
  for (; i < count; ++i) out[i] = aligned_value(level[i], table[offset[i]]);
}

// Eight steps of a row must share one block of D8 (window a multiple of 64).
bool vq_window_applies(std::uint32_t window) { return window % 64 == 0 && lanes_active(); }

#if PNB_X86_KERNELS
bool vq_window(float lo, float scale, const std::uint16_t* mean_q, const float* c8, const std::uint8_t* i8,
               const float* cw, std::uint32_t window, const std::uint8_t* iw, std::uint64_t count, float* out,
               std::uint64_t stride, std::uint32_t steps, const ResidualLanes* residual) {
  if (!vq_window_applies(window) || count < kLanes) return false;
  const std::uint64_t i = lane_part(count);
  if (residual) {
    if (i != count || count > kResidualChunk) return false;
    vq_window_lanes<true>(lo, scale, mean_q, c8, i8, cw, window, iw, i, out, stride, steps, residual);
    return true;
  }
  if (lane_isa() >= LaneIsa::avx512)
    vq_window_lanes512(lo, scale, mean_q, c8, i8, cw, window, iw, i, out, stride, steps);
  else
    vq_window_lanes<false>(lo, scale, mean_q, c8, i8, cw, window, iw, i, out, stride, steps, nullptr);
  const std::uint32_t block = window / 8;
  for (std::uint64_t v = i; v < count; ++v) {
    const float mean = dequantise_mean(lo, scale, mean_q[v]);
    for (std::uint32_t t = 0; t < steps; ++t)
      out[std::uint64_t(t) * stride + v] =
          vq_value(mean, c8[std::ptrdiff_t(i8[v]) * 8 + t / block], cw[std::ptrdiff_t(iw[v]) * window + t]);
  }
  return true;
}
#endif  // PNB_X86_KERNELS

void mean_plus_entries(float lo, float scale, const std::uint16_t* mean_q, const float* t8, const std::uint8_t* i8,
                       std::uint64_t count, float* out) {
  std::uint64_t i = lane_part(count);
#if PNB_X86_KERNELS
  if (i) mean_plus_entries_lanes(lo, scale, mean_q, t8, i8, i, out);
#endif
  for (; i < count; ++i) out[i] = dequantise_mean(lo, scale, mean_q[i]) + t8[std::ptrdiff_t(i8[i]) * 8];
}

void vq_step_values(float lo, float scale, const std::uint16_t* mean_q, const float* t8, const std::uint8_t* i8,
                    const float* tw, std::int32_t stride, const std::uint8_t* iw, std::uint64_t count, float* out) {
  std::uint64_t i = lane_part(count);
#if PNB_X86_KERNELS
  if (i) vq_step_values_lanes(lo, scale, mean_q, t8, i8, tw, stride, iw, i, out);
#endif
  for (; i < count; ++i)
    out[i] = vq_value(dequantise_mean(lo, scale, mean_q[i]), t8[std::ptrdiff_t(i8[i]) * 8],
                      tw[std::ptrdiff_t(iw[i]) * stride]);
}

void aligned_step_values(float lo, float scale, const std::uint16_t* mean_q, const float* table,
                         const std::uint8_t* ia, const std::uint8_t* shift, std::int32_t stride, std::uint64_t count,
                         float* out) {
  std::uint64_t i = lane_part(count);
#if PNB_X86_KERNELS
  if (i) aligned_step_values_lanes(lo, scale, mean_q, table, ia, shift, stride, i, out);
#endif
  for (; i < count; ++i)
    out[i] = aligned_value(dequantise_mean(lo, scale, mean_q[i]), table[std::ptrdiff_t(ia[i]) * stride - shift[i]]);
}

}  // namespace penumbra::compression::detail
