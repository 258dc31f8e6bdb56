// SPDX-License-Identifier: BSD-3-Clause
// compression/src/lane_blocks_encoder.cpp -- the predictive coder's integers written as lane
// blocks (lane_blocks.h): chunks of blocks in parallel, then their columns joined at bit offsets.
#include <algorithm>
#include <bit>
#include <cmath>
#include <vector>

#include "lane_blocks.h"
#include "round_to_integer.h"
#include "penumbra/core/thread_pool.h"

namespace penumbra::compression::detail {

namespace {

// Bits of a two's-complement slot that holds d: -2^(w-1) <= d < 2^(w-1); width 0 holds only 0.
std::uint32_t signed_width(std::int32_t d) {
  return d == 0 ? 0u : bit_width(std::uint32_t(d ^ (d >> 31))) + 1;
}

// One chunk's blocks, with its columns starting at bit 0 (placed at their offset when joined).
struct Chunk {
  std::vector<std::uint8_t> widths;
  std::vector<std::uint8_t> transient_ends;
  std::vector<std::uint16_t> linear, raw, exception_rows, exception_steps, exception_lanes;
  std::vector<std::uint32_t> highs;  // zigzag high parts, each at its block's width
  std::vector<float> raw_values;
  std::vector<std::uint32_t> words;
  std::uint64_t bits = 0;

  // Writes `value` (`width` bits) at bit `pos` of lane `lane`'s column.
  void put(std::uint32_t lane, std::uint64_t pos, std::uint32_t width, std::uint32_t value) {
    if (width == 0) return;
    const std::uint64_t row = pos >> 5;
    const std::uint32_t sh = std::uint32_t(pos & 31);
    if ((row + 2) * kLaneBlock > words.size()) words.resize((row + 2) * kLaneBlock * 2, 0);
    words[row * kLaneBlock + lane] |= value << sh;
    if (sh + width > 32) words[(row + 1) * kLaneBlock + lane] |= value >> (32 - sh);
  }
};

constexpr std::uint64_t kChunkBlocks = 64;

// The page's quantiser (k = round((x - lo) / step), held within `bound`), shape and layout.
struct Quantiser {
  std::uint32_t steps, window, first_width;
  float lo, step, bound;
  LaneLayout layout;
};

// What an exception row is priced at when a span's width is chosen. It stores 32 bits (step and
// lanes) and a high part per lane, but each row also breaks the decoder's step loop (a load of
// its lanes, an expand, a test per step of its span). On mug at 1e-3 and 1e-2, against 32 bits:
// 64 decodes a window 1-12 % faster at 1.5-1.7 % more bytes; 96 and 128 add 1-5 % speed but
// cost 3-9 % of the ratio.
constexpr std::uint64_t kRowPriceBits = 64;

// A block's errors d[l * n + t] counted per step, as sums over steps [0, t), so that the cheapest
// width of any span of steps costs O(33) whatever its length:
//   wider[t][c]: slots wider than c bits; rows[t][c]: steps whose widest slot is wider than c.
class SpanCosts {
 public:
  static constexpr std::uint32_t kWidths = 33;  // a slot's signed width is 0..32
  struct Choice {
    std::uint32_t width;
    std::uint64_t bits;
  };

  void count(const std::int32_t* d, std::uint32_t n) {
    // Only widths up to the block's widest slot are ever asked for (cheapest stops there), and
    // they are usually a few of the 33: the counts keep that many per step.
    m_slot.resize(std::size_t(n) * kLaneBlock);
    std::uint32_t top = 0;
    for (std::uint32_t t = 0; t < n; ++t)
      for (std::uint64_t l = 0; l < kLaneBlock; ++l) {
        const std::uint32_t w = signed_width(d[l * n + t]);
        m_slot[std::size_t(t) * kLaneBlock + l] = std::uint8_t(w);
        top = std::max(top, w);
      }
    m_stride = top + 1;
    m_wider.assign(std::size_t(n + 1) * m_stride, 0);
    m_rows.assign(std::size_t(n + 1) * m_stride, 0);
    for (std::uint32_t t = 0; t < n; ++t) {
      std::uint32_t histogram[kWidths + 1] = {}, widest = 0;
      for (std::uint64_t l = 0; l < kLaneBlock; ++l) {
        const std::uint32_t w = m_slot[std::size_t(t) * kLaneBlock + l];
        ++histogram[w];
        widest = std::max(widest, w);
      }
      const std::uint32_t* wider = &m_wider[std::size_t(t) * m_stride];
      const std::uint32_t* rows = &m_rows[std::size_t(t) * m_stride];
      std::uint32_t* next_wider = &m_wider[std::size_t(t + 1) * m_stride];
      std::uint32_t* next_rows = &m_rows[std::size_t(t + 1) * m_stride];
      std::uint32_t above = 0;
      for (std::uint32_t c = m_stride; c-- > 0;) {
        above += histogram[c + 1];
        next_wider[c] = wider[c] + above;
        next_rows[c] = rows[c] + (widest > c);
      }
    }
  }

  // The width for steps [a, e) with the fewest bits, counting each exception row at
  // kRowPriceBits and each high part at its most (wmax - w + 1 bits); width 0 for no steps.
  Choice cheapest(std::uint32_t a, std::uint32_t e) const {
    if (e <= a) return {0, 0};
    const std::uint32_t *wider_a = &m_wider[std::size_t(a) * m_stride], *wider_e = &m_wider[std::size_t(e) * m_stride];
    const std::uint32_t *rows_a = &m_rows[std::size_t(a) * m_stride], *rows_e = &m_rows[std::size_t(e) * m_stride];
    std::uint32_t wmax = 0;
    while (rows_e[wmax] != rows_a[wmax]) ++wmax;  // no step wider than wmax (rows[.][top] is 0)
    Choice best{wmax, ~0ull};
    for (std::uint32_t c = 0; c <= wmax; ++c) {
      const std::uint64_t exceptions = wider_e[c] - wider_a[c], rows = rows_e[c] - rows_a[c];
      const std::uint64_t bits = kLaneBlock * std::uint64_t(e - a) * c + kRowPriceBits * rows + exceptions * (wmax - c + 1);
      if (bits < best.bits) best = {c, bits};
    }
    return best;
  }

 private:
  std::vector<std::uint32_t> m_wider, m_rows;  // per step, m_stride widths
  std::vector<std::uint8_t> m_slot;             // each slot's signed width, step by step
  std::uint32_t m_stride = kWidths;
};

// The latest transient end the encoder tries before the window's own end: a run's transient lies
// in its first steps, and trying every end of a 1024-step window would cost more than the rest
// of the block's encoding.
constexpr std::uint32_t kLaneTransientSearch = 64;

// A block's widths after step 1 and its transient end.
struct BlockLayout {
  std::uint32_t w2, w3, w, end;
};

BlockLayout choose_layout(const SpanCosts& costs, std::uint32_t n, LaneLayout layout) {
  const std::uint32_t start = lane_transient_start(n);
  if (layout != LaneLayout::chosen) {
    // Format version 4's transient steps 2 .. 5 (version 3: every step) share one width.
    const std::uint32_t end = std::min(n, kOlderLaneTransientEnd), shared_end = layout == LaneLayout::transient_to_6 ? end : n;
    const std::uint32_t shared = costs.cheapest(std::min(n, 2u), shared_end).width;
    const std::uint32_t later = layout == LaneLayout::transient_to_6 ? costs.cheapest(end, n).width : shared;
    return {n > 2 ? shared : 0, end > 3 ? shared : 0, end < n ? later : 0, end};
  }
  // Each transient end up to kLaneTransientSearch, and the window's end if a byte holds it: two
  // spans' cheapest widths each; the fewest bits win, the earliest end on a tie.
  BlockLayout best{costs.cheapest(std::min(n, 2u), start).width, 0, 0, start};
  std::uint64_t fewest = ~0ull;
  const auto consider = [&](std::uint32_t end) {
    const SpanCosts::Choice transient = costs.cheapest(start, end), later = costs.cheapest(end, n);
    if (transient.bits + later.bits < fewest) {
      fewest = transient.bits + later.bits;
      best.w3 = transient.width, best.w = later.width, best.end = end;
    }
  };
  const std::uint32_t last = std::min(n, kLaneTransientSearch);
  for (std::uint32_t end = start; end <= last; ++end) consider(end);
  if (last < n && n <= kLaneMaxTransientEnd) consider(n);
  return best;
}

// Encodes one block of `lanes` vertices (x: their windows, q.window floats apart) into c.
void encode_block(const float* x, std::uint64_t lanes, const Quantiser& q, Chunk& c, std::vector<std::int32_t>& d,
                  std::vector<std::uint32_t>& kk, SpanCosts& costs) {
  const std::uint32_t n = q.steps, fw = q.first_width;
  const float lo = q.lo, step = q.step, bound = q.bound;
  // k_0 per lane and each step's difference from its prediction, d[l * n + t]; raw lanes and
  // padding read 0 everywhere.
  std::uint32_t k0[kLaneBlock] = {};
  std::uint16_t raw = 0, linear = 0;
  d.assign(kLaneBlock * std::size_t(n), 0);
  kk.resize(n);
  for (std::uint64_t l = 0; l < lanes; ++l) {
    const float* xl = x + l * q.window;
    bool fits = true;
    for (std::uint32_t t = 0; t < n && fits; ++t) {
      const double kd = round_to_integer((double(xl[t]) - lo) / step);
      const float rebuilt = lo + float(kd) * step;
      fits = kd >= 0 && kd < double(1ull << fw) && std::fabs(double(xl[t]) - double(rebuilt)) <= bound;
      kk[t] = fits ? std::uint32_t(kd) : 0;
    }
    if (!fits) {
      raw |= std::uint16_t(1u << l);
      c.raw_values.insert(c.raw_values.end(), xl, xl + n);
      continue;
    }
    k0[l] = kk[0];
    // Whichever predictor needs fewer bits over steps 2.. (step 1 predicts k_0 either way).
    std::uint64_t cost[2] = {0, 0};
    for (std::uint32_t t = 2; t < n; ++t) {
      cost[0] += signed_width(std::int32_t(kk[t] - kk[t - 1]));
      cost[1] += signed_width(std::int32_t(kk[t] - (2u * kk[t - 1] - kk[t - 2])));
    }
    const bool extrapolate = cost[1] < cost[0];
    if (extrapolate) linear |= std::uint16_t(1u << l);
    for (std::uint32_t t = 1; t < n; ++t) {
      const std::uint32_t prediction = extrapolate && t >= 2 ? 2u * kk[t - 1] - kk[t - 2] : kk[t - 1];
      d[l * n + t] = std::int32_t(kk[t] - prediction);
    }
  }
  // Step 1 gets the width of its widest lane; step 2, the transient steps and the later ones each
  // the width with the fewest bits over their steps.
  std::uint32_t w1 = 0;
  if (n >= 2)
    for (std::uint64_t l = 0; l < kLaneBlock; ++l) w1 = std::max(w1, signed_width(d[l * n + 1]));
  costs.count(d.data(), n);
  const BlockLayout layout = choose_layout(costs, n, q.layout);
  // Slots, exception rows and high parts.
  std::uint64_t pos = c.bits;
  for (std::uint64_t l = 0; l < kLaneBlock; ++l) c.put(std::uint32_t(l), pos, fw, k0[l]);
  pos += fw;
  std::uint32_t high_width = 0;
  const std::size_t rows_before = c.exception_steps.size();
  for (std::uint32_t t = 1; t < n; ++t) {
    const std::uint32_t width = t == 1 ? w1 : t == 2 ? layout.w2 : t < layout.end ? layout.w3 : layout.w;
    std::uint16_t lanes = 0;
    for (std::uint64_t l = 0; l < kLaneBlock; ++l) {
      const std::int32_t error = d[l * n + t];
      const std::uint32_t low = std::uint32_t(error) & low_mask(width);
      c.put(std::uint32_t(l), pos, width, low);
      if (signed_width(error) > width) {
        // Exact: error minus its signed low bits is a multiple of 2^width (width < 32 here).
        const std::int64_t rest = std::int64_t(error) - std::int32_t(sign_extend(low, width));
        const std::int32_t high = std::int32_t(rest >> width);
        lanes |= std::uint16_t(1u << l);
        c.highs.push_back(zigzag(high));
        high_width = std::max(high_width, bit_width(zigzag(high)));
      }
    }
    if (lanes) {
      c.exception_steps.push_back(std::uint16_t(t));
      c.exception_lanes.push_back(lanes);
    }
    pos += width;
  }
  c.exception_rows.push_back(std::uint16_t(c.exception_steps.size() - rows_before));
  c.widths.insert(c.widths.end(), {std::uint8_t(w1), std::uint8_t(layout.w2), std::uint8_t(layout.w3),
                                   std::uint8_t(layout.w), std::uint8_t(high_width)});
  c.transient_ends.push_back(std::uint8_t(layout.end));
  c.linear.push_back(linear);
  c.raw.push_back(raw);
  c.bits = pos;
}

// A thread's buffers for encode_block, kept between windows. Looked up once per call: a
// thread_local in a shared library is reached through a call (__tls_get_addr), and with
// encode_block inlined GCC repeated that call at each use in its loops (6.5M calls, 1.5 % of an
// encode at 1e-3).
struct BlockScratch {
  std::vector<float> x;
  std::vector<std::int32_t> d;
  std::vector<std::uint32_t> k;
  SpanCosts costs;
};
__attribute__((noinline)) BlockScratch& block_scratch() {
  thread_local BlockScratch scratch;
  return scratch;
}

}  // namespace

LaneBlocks build_lane_blocks(std::uint64_t N, std::uint32_t steps, std::uint32_t window, float lo, float step,
                             float bound, std::uint32_t first_width,
                             const std::function<void(std::uint64_t, std::uint64_t, float*)>& gather,
                             LaneLayout layout) {
  const std::uint64_t B = lane_block_count(N), chunks = (B + kChunkBlocks - 1) / kChunkBlocks;
  const Quantiser q{steps, window, first_width, lo, step, bound, layout};
  std::vector<Chunk> done(chunks);
  parallel_for(chunks, 1, [&](std::size_t c0, std::size_t c1) {
    BlockScratch& s = block_scratch();
    for (std::size_t c = c0; c < c1; ++c) {
      Chunk& chunk = done[c];
      const std::uint64_t first = c * kChunkBlocks * kLaneBlock, count = std::min(N - first, kChunkBlocks * kLaneBlock);
      s.x.resize(count * window);
      gather(first, count, s.x.data());
      for (std::uint64_t v = 0; v < count; v += kLaneBlock)
        encode_block(s.x.data() + v * window, std::min<std::uint64_t>(kLaneBlock, count - v), q, chunk, s.d, s.k, s.costs);
    }
  });
  // Join: tables concatenated, each chunk's columns ORed in at its bit offset, high parts packed.
  LaneBlocks L;
  std::uint64_t bits = 0;
  for (const Chunk& c : done) bits += c.bits;
  const std::uint64_t rows = lane_word_rows(bits);
  L.words.assign((1 + rows + 2) * kLaneBlock, 0);  // the zero row, the rows, room for the last chunk's carry
  std::uint32_t* columns = L.words.data() + kLaneBlock;
  std::vector<std::uint8_t> high_bytes;
  BitWriter high_writer(high_bytes);
  std::uint64_t at = 0;
  for (const Chunk& c : done) {
    L.widths.insert(L.widths.end(), c.widths.begin(), c.widths.end());
    L.transient_ends.insert(L.transient_ends.end(), c.transient_ends.begin(), c.transient_ends.end());
    L.linear.insert(L.linear.end(), c.linear.begin(), c.linear.end());
    L.raw.insert(L.raw.end(), c.raw.begin(), c.raw.end());
    L.exception_rows.insert(L.exception_rows.end(), c.exception_rows.begin(), c.exception_rows.end());
    L.exception_steps.insert(L.exception_steps.end(), c.exception_steps.begin(), c.exception_steps.end());
    L.exception_lanes.insert(L.exception_lanes.end(), c.exception_lanes.begin(), c.exception_lanes.end());
    L.raw_values.insert(L.raw_values.end(), c.raw_values.begin(), c.raw_values.end());
    std::size_t h = 0, r = 0;
    for (std::size_t b = 0; b < c.linear.size(); ++b) {
      const std::uint32_t x = c.widths[kLaneWidths * b + 4];
      for (std::uint32_t e = 0; e < c.exception_rows[b]; ++e, ++r)
        for (int lane = std::popcount(c.exception_lanes[r]); lane > 0; --lane) high_writer.put(c.highs[h++], x);
    }
    const std::uint64_t base = at >> 5, used = (c.bits + 31) / 32;
    const std::uint32_t sh = std::uint32_t(at & 31);
    for (std::uint64_t row = 0; row < used && row * kLaneBlock < c.words.size(); ++row)
      for (std::uint64_t l = 0; l < kLaneBlock; ++l) {
        const std::uint32_t v = c.words[row * kLaneBlock + l];
        columns[(base + row) * kLaneBlock + l] |= v << sh;
        if (sh) columns[(base + row + 1) * kLaneBlock + l] |= v >> (32 - sh);
      }
    at += c.bits;
  }
  L.words.resize(lane_words_held(bits));
  L.words.shrink_to_fit();  // as a parsed page holds them: a read past the rows is caught in tests
  high_writer.flush();
  high_bytes.resize(high_bytes.size() + 8, 0);
  L.exception_bits = std::move(high_bytes);
  return L;
}

}  // namespace penumbra::compression::detail
