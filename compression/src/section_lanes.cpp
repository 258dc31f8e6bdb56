// SPDX-License-Identifier: BSD-3-Clause
// compression/src/section_lanes.cpp
#include "section_lanes.h"

#include <algorithm>
#include <atomic>
#include <cstring>

#include "bit_io.h"
#include "cpu_features.h"
#include "cursor_state.h"
#include "lane_ops.h"
#include "penumbra/compression/window_codec.h"
#include "value_layout.h"
#include "vertex_section.h"

namespace penumbra::compression {

namespace {
std::atomic<bool> g_vector_decode{true};
}

void set_vector_decode(bool enabled) { g_vector_decode.store(enabled, std::memory_order_relaxed); }
bool vector_decode_active() { return detail::lanes_active(); }

namespace detail {

bool lanes_active() {
  static const bool cpu_has_avx2 = cpu_features().avx2;
  return cpu_has_avx2 && g_vector_decode.load(std::memory_order_relaxed);
}

// The lane kernels below are AVX2 code: a build without x86 kernels has only the scalar decoders
// (lanes_active() is false there, and the callers' lane branches are compiled out).
#if PNB_X86_KERNELS

namespace {

// Everything a lane block reads once: its codes, which lanes are special (patched or raw,
// left to the scalar path), their plain widths (0 for special lanes, which then read only the
// first bits of their own section, inside the payload) and the section starts relative to the
// group's first byte.
struct Block {
  __m256i width, section;
  const std::uint8_t* group;
  int special_mask;
  bool all_zero;
};

// The 4-bit codes of the 8 vertices from v (a multiple of 8), low nibble first.
PNB_LANES std::uint32_t packed_codes(const EncodedPage& p, std::uint64_t v) {
  std::uint32_t packed;
  std::memcpy(&packed, p.blocks.widths.data() + v / 2, 4);
  return packed;
}
PNB_LANES __m256i unpack_codes(std::uint32_t packed) {
  return _mm256_and_si256(
      _mm256_srlv_epi32(_mm256_set1_epi32(int(packed)), _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28)),
      _mm256_set1_epi32(0xF));
}

PNB_LANES Block load_block(const EncodedPage& p, std::uint64_t v) {
  Block k;
  const std::uint32_t packed = packed_codes(p, v);
  k.all_zero = packed == 0;
  const __m256i codes = unpack_codes(packed);
  const __m256i special = _mm256_cmpgt_epi32(codes, _mm256_set1_epi32(int(kMaxPlainWidth)));
  k.special_mask = _mm256_movemask_ps(_mm256_castsi256_ps(special));
  k.width = _mm256_andnot_si256(special, codes);
  k.section = load(p.blocks.section_bits.data() + v);
  // The 8 vertices of a block share a group (kGroupSize is a multiple of 8).
  k.group = p.blocks.payload.data() + p.blocks.group_offsets[v / BitBlocks::kGroupSize];
  return k;
}

// Appends the vertices of the lanes set in `mask` (block starting at v).
PNB_LANES void list_lanes(int mask, std::uint64_t v, std::vector<std::uint64_t>& out) {
  for (int m = mask; m; m &= m - 1) out.push_back(v + std::uint64_t(__builtin_ctz(unsigned(m))));
}

// The sizeof(Word) bytes from `group + byte[l]` of each lane l. Eight scalar loads, not a gather:
// gathers are slow on an AMD Zen 5, and without them one-step decodes of bit sections ran 11-20 %
// faster (mug and eeg, three alternated runs), eeg's predictive windows 12 % and its residual
// ones 4-16 % (100K vertices, medians of four alternated runs); mug's windows within 4 %.
template <class Word>
PNB_LANES void lane_words(const std::uint8_t* group, __m256i byte, Word (&word)[kLanes]) {
  alignas(32) std::uint32_t at[kLanes];
  store(at, byte);
  for (std::uint64_t l = 0; l < kLanes; ++l) std::memcpy(&word[l], group + at[l], sizeof(Word));
}

// `width` bits at bit offset `bit` from `group`, per lane: 4 bytes hold any plain value (<= 13
// bits after a shift of <= 7); the payload's 8 bytes of padding cover the last one.
PNB_LANES __m256i read_lanes(const std::uint8_t* group, __m256i bit, __m256i width) {
  int bytes[kLanes];
  lane_words(group, _mm256_srli_epi32(bit, 3), bytes);
  const __m256i word = _mm256_setr_epi32(bytes[0], bytes[1], bytes[2], bytes[3], bytes[4], bytes[5], bytes[6], bytes[7]);
  const __m256i mask = _mm256_sub_epi32(_mm256_sllv_epi32(_mm256_set1_epi32(1), width), _mm256_set1_epi32(1));
  return _mm256_and_si256(_mm256_srlv_epi32(word, _mm256_and_si256(bit, _mm256_set1_epi32(7))), mask);
}

// The prediction of k_t (predictive_layout.h) for lanes whose predictor bit is set in `linear`.
PNB_LANES __m256i predict_lanes(__m256i linear, std::uint32_t t, __m256i k1, __m256i k2) {
  if (t < 2) return k1;
  const __m256i extrapolated = _mm256_sub_epi32(_mm256_add_epi32(k1, k1), k2);
  return _mm256_blendv_epi8(k1, extrapolated, linear);
}

}  // namespace

__attribute__((target("avx2"))) void residual_step_lanes(const EncodedPage& p, std::uint32_t t, std::uint64_t b,
                                                         std::uint64_t e, float* out,
                                                         std::vector<std::uint64_t>& special) {
  const __m256 step = _mm256_set1_ps(p.quantiser.step);
  const __m256i tt = _mm256_set1_epi32(int(t));
  for (std::uint64_t v = b; v < e; v += kLanes) {
    const Block k = load_block(p, v);
    if (k.all_zero) continue;  // sparse residuals: nothing to add
    list_lanes(k.special_mask, v, special);
    const __m256i z = read_lanes(k.group, _mm256_add_epi32(k.section, _mm256_mullo_epi32(tt, k.width)), k.width);
    const __m256 base = load(out + v);
    // Width 0 leaves the VQ value untouched (keeps -0.0f), as the scalar decoders do.
    const __m256 adds = _mm256_castsi256_ps(_mm256_cmpgt_epi32(k.width, _mm256_setzero_si256()));
    store(out + v, _mm256_blendv_ps(base, add_scaled(base, unzigzag_lanes(z), step), adds));
  }
}

__attribute__((target("avx2"))) void cursor_step_lanes(const EncodedPage& p, std::uint32_t t, std::uint64_t b,
                                                       std::uint64_t e, float* out, CursorState& s) {
  const bool predictive = p.method == PageMethod::predictive;
  const std::uint32_t i = predictive ? t - 1 : t;
  const __m256i index = _mm256_set1_epi32(int(i)), one = _mm256_set1_epi32(1);
  const __m256 lo = _mm256_set1_ps(p.quantiser.lo), step = _mm256_set1_ps(p.quantiser.step);
  alignas(32) std::uint32_t patched[kLanes];
  for (std::uint64_t v = b; v < e; v += kLanes) {
    const std::uint32_t packed = packed_codes(p, v);
    if (!predictive && packed == 0) continue;  // sparse residuals: nothing to add
    const std::uint8_t* group = p.blocks.payload.data() + p.blocks.group_offsets[v / BitBlocks::kGroupSize];
    const __m256i width = widen8(s.width.data() + v);
    const __m256i slot = load(s.slot.data() + v);
    const __m256i next = widen16(s.next.data() + v);
    __m256i z = read_lanes(group, _mm256_add_epi32(slot, _mm256_mullo_epi32(index, width)), width);
    // Exceptions are rare (a few per vertex-window): the lanes that meet one read it alone.
    if (const int hits = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(next, index)))) {
      store(patched, z);
      for (int m = hits; m; m &= m - 1) {
        const int l = __builtin_ctz(unsigned(m));
        patched[l] = take_exception(p, v + std::uint64_t(l), s);
      }
      z = load(patched);
    }
    if (predictive) {
      const __m256i linear = _mm256_cmpeq_epi32(widen8(s.linear.data() + v), one);
      const __m256i k1 = load(s.k1.data() + v), k2 = load(s.k2.data() + v);
      const __m256i k = _mm256_add_epi32(predict_lanes(linear, t, k1, k2), unzigzag_lanes(z));
      store(out + v, add_scaled(lo, k, step));
      store(s.k1.data() + v, k);
      store(s.k2.data() + v, k1);
    } else {
      // Code 0 (all zero) leaves the VQ value untouched (keeps -0.0f), as the scalar path does.
      const __m256 adds = _mm256_castsi256_ps(_mm256_cmpgt_epi32(unpack_codes(packed), _mm256_setzero_si256()));
      const __m256 base = load(out + v);
      store(out + v, _mm256_blendv_ps(base, add_scaled(base, unzigzag_lanes(z), step), adds));
    }
  }
}

// Helpers of the lane parse (window decodes and the cursor's seek) follow in the anonymous
// namespace below; seek_lanes is defined after them.

namespace {

// A whole-window decode runs a chunk of vertices in lockstep, step by step, so that each step's
// row gets a contiguous run: with one lane block per pass, the rows took 32 bytes each, more
// concurrent write streams than the caches prefetch, and the decode ran at a third of memcpy
// when its output was not already cached. Measured best for predictive pages: 64 vertices (256
// bytes per row). They had taken 1024 (4 KB rows) on a machine with 4-byte gathers per value;
// with the lanes' slots unpacked from 8-byte buffers, 1024 lanes of unpacked values (half a
// megabyte for 128 steps) no longer fit the caches and ran at 4.5-5 GB/s against 11-12.5 with
// 64, from memory as from cache (100K vertices x 128 steps). Residual chunks: kResidualChunk
// (section_lanes.h).
constexpr std::uint64_t kPredictiveChunk = 64;

// A predictive chunk's stores go to as many rows as the window has steps, each a separate
// stream, too many for the hardware prefetchers to follow: every row's first store of a chunk
// missed, and the decode stalled on memory while it had work to do (a vector variant 1.3x faster
// in cache ran no faster from memory). So each row's lines of the chunk two ahead are fetched
// while this chunk writes the row: 19-22 % faster on 100K-vertex predictive windows (medians of
// six alternated runs; one chunk ahead gained less). Residual windows add to rows the VQ pass has
// just written, still cached: prefetching them cost 4-5 %.
constexpr std::uint64_t kRowPrefetchChunks = 2;

// The lines of `lanes` floats from `at` (a chunk's part of one row).
PNB_LANES void prefetch_row(const float* at, std::uint64_t lanes) {
  for (std::uint64_t q = 0; q < lanes; q += 64 / sizeof(float))
    _mm_prefetch(reinterpret_cast<const char*>(at + q), _MM_HINT_T0);
}

// Each lane's values (zigzag integers) unpacked step-major, patched lanes' exceptions written
// over their slots; then the prediction chain or the residual add runs on whole vectors.
template <std::uint64_t kWidth, std::uint64_t kStride = kWidth>
struct WindowChunk {
  static constexpr std::uint64_t kRowStride = kStride;  // z's values between one step and the next
  alignas(32) std::int32_t first[kWidth], linear[kWidth], adds[kWidth];
  /// Value i of lane j at z[i * kStride + j]. Thread-local and kept for the life of the worker
  /// threads: at most 270 KiB (a residual chunk of kResidualChunkSteps; 64 lanes of 1024 steps:
  /// 256 KiB).
  std::vector<std::uint32_t> z;
};

// The 8 bytes from `group + byte[l]` of each lane l, as 64-bit lanes: lanes 0, 2, 4, 6 in `even`
// and 1, 3, 5, 7 in `odd`.
PNB_LANES void load_words(const std::uint8_t* group, __m256i byte, __m256i& even, __m256i& odd) {
  long long word[kLanes];
  lane_words(group, byte, word);
  even = _mm256_setr_epi64x(word[0], word[2], word[4], word[6]);
  odd = _mm256_setr_epi64x(word[1], word[3], word[5], word[7]);
}

// 32-bit results of the even lanes (in the low halves of `even`'s 64-bit lanes) and of the odd
// lanes (likewise in `odd`) back in lane order. The high halves must be zero.
PNB_LANES __m256i in_lane_order(__m256i even, __m256i odd) { return _mm256_or_si256(even, _mm256_slli_epi64(odd, 32)); }

// The predictor bit and k_0 (1 + first_width <= 32 bits) of 8 predictive sections at bits
// `section` from `group`: 8-byte words, since k_0 may be wider than read_lanes holds (the
// payload's 8 bytes of padding cover the last section's).
PNB_LANES void predictive_heads(const std::uint8_t* group, __m256i section, std::uint32_t first_width,
                                __m256i& predictor, __m256i& first) {
  const __m256i low = _mm256_set1_epi64x(0xFFFFFFFF), one = _mm256_set1_epi64x(1);
  const __m256i shift = _mm256_and_si256(section, _mm256_set1_epi32(7));
  __m256i even, odd;
  load_words(group, _mm256_srli_epi32(section, 3), even, odd);
  even = _mm256_srlv_epi64(even, _mm256_and_si256(shift, low));
  odd = _mm256_srlv_epi64(odd, _mm256_srli_epi64(shift, 32));
  const __m256i mask = _mm256_set1_epi64x(static_cast<long long>((1ull << first_width) - 1));
  predictor = in_lane_order(_mm256_and_si256(even, one), _mm256_and_si256(odd, one));
  first = in_lane_order(_mm256_and_si256(_mm256_srli_epi64(even, 1), mask), _mm256_and_si256(_mm256_srli_epi64(odd, 1), mask));
}

// Unpacks `count` values of the 8 lanes from bit `bit` (per lane, relative to `group`), `w` bits
// each, into lanes j0..j0+7 of the chunk, step-major.
template <class Chunk>
PNB_LANES void unpack_slots(const std::uint8_t* group, __m256i bit, __m256i w, std::uint64_t j0, std::uint32_t count,
                            Chunk& c) {
  // A gather per value index was most of a window decode (a 4-byte gather is microcoded, about
  // 4 ns for 8 lanes on some CPUs). Instead each lane keeps the 8 bytes from the byte holding its
  // next value, refilled every `run` indices: at most 7 bits of offset plus run slots of the
  // block's widest lane fit in the 64 bits. Even lanes sit in the low half of each 64-bit
  // lane of `even`, odd lanes in `odd`, so that one shift and a blend put them back in order.
  alignas(32) std::uint32_t widths[kLanes];
  store(widths, w);
  const std::uint32_t widest = *std::max_element(widths, widths + kLanes);
  const std::uint32_t run = widest ? (64 - 7) / widest : count;
  const __m256i low = _mm256_set1_epi64x(0xFFFFFFFF);
  const __m256i w_even = _mm256_and_si256(w, low), w_odd = _mm256_srli_epi64(w, 32);
  // Slot widths are at most 31 bits, so each lane's value is masked in 32 bits after the even
  // and odd results are put back in order (one mask instead of one per half).
  const __m256i mask = _mm256_sub_epi32(_mm256_sllv_epi32(_mm256_set1_epi32(1), w), _mm256_set1_epi32(1));
  std::uint32_t* z = c.z.data() + j0;
  for (std::uint32_t i = 0; i < count;) {
    const __m256i byte = _mm256_srli_epi32(bit, 3), offset = _mm256_and_si256(bit, _mm256_set1_epi32(7));
    __m256i even, odd;
    load_words(group, byte, even, odd);
    __m256i at_even = _mm256_and_si256(offset, low), at_odd = _mm256_srli_epi64(offset, 32);
    const std::uint32_t end = std::min(count, i + run);
    bit = _mm256_add_epi32(bit, _mm256_mullo_epi32(w, _mm256_set1_epi32(int(end - i))));
    for (; i < end; ++i, z += Chunk::kRowStride) {
      const __m256i e = _mm256_srlv_epi64(even, at_even);
      const __m256i o = _mm256_slli_epi64(_mm256_srlv_epi64(odd, at_odd), 32);
      store(z, _mm256_and_si256(_mm256_blend_epi32(e, o, 0xAA), mask));
      at_even = _mm256_add_epi64(at_even, w_even);
      at_odd = _mm256_add_epi64(at_odd, w_odd);
    }
  }
}

// Where the values of 8 sections lie, from where each one's values (or, for a patched section,
// its header) start and the lanes' 4-bit codes. A patched header holds the slot width (4 bits),
// the exception count (4) and the exception width (5); the exception list follows it, then the
// slots. Plain lanes have no exceptions (count and width 0).
struct LaneValues {
  __m256i patched;                  ///< all ones in patched lanes
  __m256i slots, width;             ///< bit of the first slot (from the group) and slot width
  __m256i list, exceptions, exception_width;
};
PNB_LANES LaneValues lane_values(const std::uint8_t* group, __m256i values, __m256i codes, std::uint32_t pb) {
  LaneValues lv;
  const __m256i zero = _mm256_setzero_si256();
  lv.patched = _mm256_cmpeq_epi32(codes, _mm256_set1_epi32(int(kPatchedCode)));
  lv.slots = values;
  lv.width = codes;
  lv.list = lv.exceptions = lv.exception_width = zero;
  if (_mm256_testz_si256(lv.patched, lv.patched)) return lv;
  const __m256i h = read_lanes(group, values, _mm256_set1_epi32(int(kPatchedHeaderBits)));
  lv.list = _mm256_add_epi32(values, _mm256_set1_epi32(int(kPatchedHeaderBits)));
  lv.exceptions = _mm256_and_si256(lv.patched, _mm256_and_si256(_mm256_srli_epi32(h, 4), _mm256_set1_epi32(0xF)));
  lv.exception_width = _mm256_and_si256(lv.patched, _mm256_srli_epi32(h, 8));
  const __m256i skip =
      _mm256_mullo_epi32(lv.exceptions, _mm256_add_epi32(_mm256_set1_epi32(int(pb)), lv.exception_width));
  lv.slots = _mm256_blendv_epi8(values, _mm256_add_epi32(lv.list, skip), lv.patched);
  lv.width = _mm256_blendv_epi8(codes, _mm256_and_si256(h, _mm256_set1_epi32(0xF)), lv.patched);
  return lv;
}

// Writes the exceptions of a patched lane over its unpacked slots (in-range positions only).
// An entry (position, then value: at most 10 + 31 bits) is one 8-byte read after a shift of at
// most 7; the payload's 8 bytes of padding cover the last.
template <class Chunk>
void patch_lane(const std::uint8_t* data, std::uint64_t at, std::uint32_t exceptions, std::uint32_t exception_width,
                std::uint32_t count, std::uint64_t lane, Chunk& c) {
  const std::uint32_t pb = position_bits(count);
  const std::uint64_t position_mask = (1ull << pb) - 1, value_mask = (1ull << exception_width) - 1;
  std::uint32_t* z = c.z.data() + lane;
  for (std::uint32_t x = 0; x < exceptions; ++x, at += pb + exception_width) {
    std::uint64_t word;
    std::memcpy(&word, data + (at >> 3), 8);
    word >>= at & 7;
    const auto i = static_cast<std::uint32_t>(word & position_mask);
    if (i < count) z[std::uint64_t(i) * Chunk::kRowStride] = static_cast<std::uint32_t>((word >> pb) & value_mask);
  }
}

// This thread's chunk. Out of line on purpose: in a shared library the address of a
// thread_local is a call to __tls_get_addr, and GCC recomputes it at every use of the variable,
// even through a reference bound once, rather than keep it in a register (14 % of a predictive
// decode's instructions). A reference returned by a call it cannot see into is kept.
template <std::uint64_t kWidth, std::uint64_t kStride = kWidth>
[[gnu::noinline]] WindowChunk<kWidth, kStride>& thread_chunk() {
  thread_local WindowChunk<kWidth, kStride> chunk;
  return chunk;
}

// Parses the 8 sections from vertex v (once per vertex-window) and unpacks their `count` values
// into lanes j0..j0+7 of the chunk; raw vertices go to `raw`.
//
// Without a raw lane (nearly every block) the 8 sections are parsed side by side: where the
// values start, the predictor and k_0 of a predictive page, and the 13-bit header of a patched
// section (value_layout.h), whose exceptions are then written over the unpacked slots lane by
// lane. Parsed one lane at a time, its read_bits were a fifth of a predictive decode's
// instructions (callgrind, mug); in lanes, with the thread's chunk looked up once, a whole
// predictive window decodes 12-18 % faster (mug, eeg, smooth at 1e-3) and a residual one 3-6 %.
// Most sections are patched (3 in 4 on mug, 1 in 2 on eeg), so a plain-only path would rarely
// apply.
template <class Chunk>
__attribute__((target("avx2"))) void unpack_block(const EncodedPage& p, std::uint64_t v, std::uint64_t j0,
                                                  std::uint32_t count, Chunk& c, std::vector<std::uint64_t>& raw) {
  const std::uint8_t* data = p.blocks.payload.data();
  const std::uint64_t group_bit = p.blocks.group_offsets[v / BitBlocks::kGroupSize] * 8;
  const std::uint8_t* group = data + group_bit / 8;
  const __m256i codes = unpack_codes(packed_codes(p, v));
  const __m256i raw_lanes = _mm256_cmpeq_epi32(codes, _mm256_set1_epi32(int(BitBlocks::kRawWidth)));
  if (_mm256_testz_si256(raw_lanes, raw_lanes)) {
    const __m256i zero = _mm256_setzero_si256();
    const __m256i section = load(p.blocks.section_bits.data() + v);
    __m256i values = section;  // where each lane's values (or its patched header) start
    if (p.method == PageMethod::predictive) {
      __m256i predictor, first;
      predictive_heads(group, section, p.quantiser.first_width, predictor, first);
      store(c.first + j0, first);
      store(c.linear + j0, _mm256_sub_epi32(zero, predictor));  // predictor 1 (linear): -1
      values = _mm256_add_epi32(section, _mm256_set1_epi32(int(1 + p.quantiser.first_width)));
    } else {
      store(c.first + j0, zero);
      store(c.linear + j0, zero);
    }
    store(c.adds + j0, _mm256_cmpgt_epi32(codes, zero));  // code 0: nothing to add
    const LaneValues lv = lane_values(group, values, codes, position_bits(count));
    const int patched_mask = _mm256_movemask_ps(_mm256_castsi256_ps(lv.patched));
    alignas(32) std::uint32_t exceptions[kLanes], exception_width[kLanes], list[kLanes];
    if (patched_mask) {
      store(exceptions, lv.exceptions);
      store(exception_width, lv.exception_width);
      store(list, lv.list);
    }
    unpack_slots(group, lv.slots, lv.width, j0, count, c);
    for (int m = patched_mask; m; m &= m - 1) {
      const int l = __builtin_ctz(unsigned(m));
      patch_lane(data, group_bit + list[l], exceptions[l], exception_width[l], count, j0 + std::uint64_t(l), c);
    }
    return;
  }
  alignas(32) std::uint32_t slot[kLanes], width[kLanes];
  VertexSection s;
  int patched = 0;
  ValueSpan spans[kLanes];
  for (std::uint64_t l = 0; l < kLanes; ++l) {
    const std::uint32_t code = p.blocks.width(v + l);
    parse_vertex(p, data, group_bit + p.blocks.section_bits[v + l], code, ~0ull, s);
    const bool is_raw = code == BitBlocks::kRawWidth;
    if (is_raw) raw.push_back(v + l);
    patched |= int(code == kPatchedCode) << l;
    spans[l] = s.values;
    // A raw lane reads zero-width slots at its own start (inside the payload); the scalar
    // path writes its values afterwards.
    slot[l] = std::uint32_t((is_raw ? s.start : s.values.slots) - group_bit);
    width[l] = is_raw ? 0 : s.values.width;
    c.first[j0 + l] = std::int32_t(s.first_value);
    c.linear[j0 + l] = s.predictor == 1 ? -1 : 0;
    c.adds[j0 + l] = !is_raw && code != 0 ? -1 : 0;  // width 0 without exceptions adds nothing
  }
  unpack_slots(group, load(slot), load(width), j0, count, c);
  for (int m = patched; m; m &= m - 1) {
    const int l = __builtin_ctz(unsigned(m));
    patch_lane(data, spans[l].exception_list, spans[l].exceptions, spans[l].exception_width, count,
               j0 + std::uint64_t(l), c);
  }
}

}  // namespace

namespace {

// The residual of vertices [v0, v0 + lanes) (at most kWidth), every step, unpacked into this
// thread's chunk of kWidth lanes, its rows kStride apart.
template <std::uint64_t kWidth, std::uint64_t kStride>
__attribute__((target("avx2"))) WindowChunk<kWidth, kStride>& unpack_residual(const EncodedPage& p, std::uint64_t v0,
                                                                              std::uint64_t lanes,
                                                                              std::vector<std::uint64_t>& special) {
  const std::uint32_t n = p.step_count;
  WindowChunk<kWidth, kStride>& c = thread_chunk<kWidth, kStride>();
  c.z.resize(std::size_t(n) * kStride);
  for (std::uint64_t j = 0; j < lanes; j += kLanes) {
    if (packed_codes(p, v0 + j) != 0)
      unpack_block(p, v0 + j, j, n, c, special);
    else  // sparse residuals: an all-zero block adds nothing and is not unpacked
      store(c.adds + j, _mm256_setzero_si256());
  }
  return c;
}

// The residual pass's chunk (pages whose residual is added to VQ rows already written): 64
// vertices, 256 bytes of each row, measured best for it.
constexpr std::uint64_t kResidualPassChunk = 64;

}  // namespace

ResidualLanes unpack_residual_lanes(const EncodedPage& p, std::uint64_t v0, std::uint64_t lanes,
                                    std::vector<std::uint64_t>& special) {
  const auto& c = unpack_residual<kResidualChunk, kResidualStride>(p, v0, lanes, special);
  return {c.z.data(), c.adds, p.quantiser.step};
}

__attribute__((target("avx2"))) void residual_window_lanes(const EncodedPage& p, std::uint64_t b, std::uint64_t e,
                                                           float* window, std::vector<std::uint64_t>& special) {
  const std::uint64_t N = p.vertex_count;
  const std::uint32_t n = p.step_count;
  const __m256 step = _mm256_set1_ps(p.quantiser.step);
  constexpr std::uint64_t kChunkLanes = kResidualPassChunk;
  for (std::uint64_t v0 = b; v0 < e; v0 += kChunkLanes) {
    const std::uint64_t lanes = std::min(kChunkLanes, e - v0);
    const auto& c = unpack_residual<kChunkLanes, kChunkLanes>(p, v0, lanes, special);
    std::uint64_t active[kChunkLanes / kLanes], count = 0;
    for (std::uint64_t j = 0; j < lanes; j += kLanes)
      if (packed_codes(p, v0 + j) != 0) active[count++] = j;
    float* row = window + v0;
    const std::uint32_t* z = c.z.data();
    for (std::uint32_t t = 0; t < n; ++t, row += N, z += kChunkLanes)
      for (std::uint64_t a = 0; a < count; ++a) {
        const std::uint64_t j = active[a];
        const __m256 base = load(row + j);
        const __m256 adds = _mm256_castsi256_ps(load(c.adds + j));
        store(row + j, _mm256_blendv_ps(base, add_scaled(base, unzigzag_lanes(load(z + j)), step), adds));
      }
  }
}

__attribute__((target("avx2"))) void predictive_window_lanes(const EncodedPage& p, std::uint64_t b, std::uint64_t e,
                                                             float* window, std::vector<std::uint64_t>& special) {
  const std::uint64_t N = p.vertex_count;
  const std::uint32_t n = p.step_count;
  const __m256 lo = _mm256_set1_ps(p.quantiser.lo), step = _mm256_set1_ps(p.quantiser.step);
  constexpr std::uint64_t kChunkLanes = kPredictiveChunk;
  WindowChunk<kChunkLanes>& c = thread_chunk<kChunkLanes>();
  c.z.resize(std::size_t(n) * kChunkLanes);
  for (std::uint64_t v0 = b; v0 < e; v0 += kChunkLanes) {
    const std::uint64_t lanes = std::min(kChunkLanes, e - v0);
    for (std::uint64_t j = 0; j < lanes; j += kLanes) unpack_block(p, v0 + j, j, n - 1, c, special);
    __m256i k1[kChunkLanes / kLanes], k2[kChunkLanes / kLanes];
    float* row = window + v0;
    // The chunk two ahead, while it lies in this range (only there is the rows' memory known).
    const std::uint64_t ahead = kRowPrefetchChunks * kChunkLanes;
    const bool prefetch = v0 + ahead + kChunkLanes <= e;
    if (prefetch) prefetch_row(row + ahead, kChunkLanes);
    for (std::uint64_t j = 0; j < lanes; j += kLanes) {
      k1[j / kLanes] = k2[j / kLanes] = load(c.first + j);
      store(row + j, add_scaled(lo, k1[j / kLanes], step));
    }
    const std::uint32_t* z = c.z.data();
    for (std::uint32_t t = 1; t < n; ++t, z += kChunkLanes) {
      row += N;
      if (prefetch) prefetch_row(row + ahead, kChunkLanes);
      for (std::uint64_t j = 0; j < lanes; j += kLanes) {
        __m256i& a = k1[j / kLanes];
        const __m256i next =
            _mm256_add_epi32(predict_lanes(load(c.linear + j), t, a, k2[j / kLanes]), unzigzag_lanes(load(z + j)));
        k2[j / kLanes] = a;
        a = next;
        store(row + j, add_scaled(lo, next, step));
      }
    }
  }
}

__attribute__((target("avx2"))) std::uint64_t seek_lanes(const EncodedPage& p, std::uint64_t b, std::uint64_t e,
                                                         std::uint64_t* left_out, CursorState& s) {
  const bool predictive = p.method == PageMethod::predictive;
  const std::uint32_t pb = position_bits(value_count(p));
  const __m256i zero = _mm256_setzero_si256();
  alignas(32) std::uint32_t slot[kLanes], width[kLanes], next[kLanes], entry[kLanes], left[kLanes], xwidth[kLanes],
      linear[kLanes];
  std::uint64_t scalar = 0;
  for (std::uint64_t v = b; v < e; v += kLanes) {
    const __m256i codes = unpack_codes(packed_codes(p, v));
    const __m256i raw_lanes = _mm256_cmpeq_epi32(codes, _mm256_set1_epi32(int(BitBlocks::kRawWidth)));
    if (!_mm256_testz_si256(raw_lanes, raw_lanes)) {
      left_out[scalar++] = v;  // a raw lane: the whole block goes to the scalar seek
      continue;
    }
    const std::uint8_t* group = p.blocks.payload.data() + p.blocks.group_offsets[v / BitBlocks::kGroupSize];
    const __m256i section = load(p.blocks.section_bits.data() + v);
    __m256i values = section;
    __m256i predictor = zero;
    if (predictive) {
      // The predictor bit only: the cursor's first step reads k_0 itself.
      predictor = read_lanes(group, section, _mm256_set1_epi32(1));
      values = _mm256_add_epi32(section, _mm256_set1_epi32(int(1 + p.quantiser.first_width)));
    }
    const LaneValues lv = lane_values(group, values, codes, pb);
    // The cursor starts at value index 0: a lane's next exception is its list's first.
    const __m256i first_position = _mm256_testz_si256(lv.patched, lv.patched)
                                       ? zero
                                       : read_lanes(group, lv.list, _mm256_set1_epi32(int(pb)));
    const __m256i has = _mm256_cmpgt_epi32(lv.exceptions, zero);  // lanes with an exception to come
    store(slot, lv.slots);
    store(width, lv.width);
    store(next, _mm256_blendv_epi8(_mm256_set1_epi32(CursorState::kNoException), first_position, has));
    store(entry, _mm256_and_si256(has, lv.list));
    store(left, lv.exceptions);
    store(xwidth, lv.exception_width);
    store(linear, predictor);
    for (std::uint64_t l = 0; l < kLanes; ++l) {
      s.slot[v + l] = slot[l];
      s.width[v + l] = std::uint8_t(width[l]);
      s.next[v + l] = std::uint16_t(next[l]);
      s.entry[v + l] = entry[l];
      s.left[v + l] = std::uint8_t(left[l]);
      s.exception_width[v + l] = std::uint8_t(xwidth[l]);
    }
    if (predictive)
      for (std::uint64_t l = 0; l < kLanes; ++l) s.linear[v + l] = std::uint8_t(linear[l]);
  }
  return scalar;
}

#endif  // PNB_X86_KERNELS

}  // namespace detail
}  // namespace penumbra::compression
