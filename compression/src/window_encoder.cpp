// SPDX-License-Identifier: BSD-3-Clause
// compression/src/window_encoder.cpp -- encodes one window: VQ (mean + D8 + D_W, closed loop),
// optional quantised residual, or the error-bounded predictive coder for VQ-poor windows.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "aligned_lbg.h"
#include "bit_blocks_builder.h"
#include "bit_io.h"
#include "page_methods.h"
#include "lane_blocks.h"
#include "predictive_layout.h"
#include "round_to_integer.h"
#include "splitmix.h"
#include "value_layout.h"
#include "penumbra/compression/lbg.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "vq_value.h"

namespace penumbra::compression {

using detail::BitWriter;

namespace {

constexpr std::uint64_t kGroup = BitBlocks::kGroupSize;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Window {
  const float* data;
  std::uint64_t n_vertices;
  std::uint32_t steps;  // real steps
  std::uint32_t width;  // W (padded length)
  std::uint32_t block;  // W / 8

  // Vertex-major copy of vertices [first, first+count), padded to W by repeating the last step.
  void gather(std::uint64_t first, std::uint64_t count, float* out) const {
    for (std::uint32_t t = 0; t < width; ++t) {
      const float* row = data + std::uint64_t(std::min(t, steps - 1)) * n_vertices + first;
      for (std::uint64_t i = 0; i < count; ++i) out[i * width + t] = row[i];
    }
  }
};

// D8 of each series: means of 8 equal blocks of (x - mean).
void block_means(const Window& win, const float* x, const float* m, std::uint64_t count, float* d8) {
  for (std::uint64_t i = 0; i < count; ++i)
    for (std::uint32_t b = 0; b < 8; ++b) {
      double s = 0;
      for (std::uint32_t t = b * win.block; t < (b + 1) * win.block; ++t) s += double(x[i * win.width + t]) - m[i];
      d8[i * 8 + b] = float(s / win.block);
    }
}

// What the D_W stage must carry: x minus the decoded mean + D8 (closed loop), in the
// decoder's float arithmetic.
void remove_d8(const Window& win, const std::vector<float>& c8, const float* x, const float* m,
               const std::uint8_t* i8, std::uint64_t count, float* r) {
  for (std::uint64_t i = 0; i < count; ++i) {
    const float* c = c8.data() + std::size_t(i8[i]) * 8;
    for (std::uint32_t t = 0; t < win.width; ++t) r[i * win.width + t] = x[i * win.width + t] - (m[i] + c[t / win.block]);
  }
}

// Per-vertex codes of the VQ stages for vertices whose padded series are in `x` (count x W).
struct VqStage {
  const Window& win;
  const std::vector<float>& mean;  // dequantised mean of every vertex
  const std::vector<float>& c8;
  const std::vector<float>& cw;
  const NearestSearch& s8;
  const NearestSearch& sw;

  void detail8(const float* x, const float* m, std::uint64_t count, float* d8) const {
    block_means(win, x, m, count, d8);
  }
  void after_d8(const float* x, const float* m, const std::uint8_t* i8, std::uint64_t count, float* r) const {
    remove_d8(win, c8, x, m, i8, count, r);
  }
  std::uint32_t candidates;

  void encode(const float* x, const float* m, std::uint64_t count, std::uint8_t* i8, std::uint8_t* iw,
              std::vector<float>& scratch8, std::vector<float>& scratchw) const {
    scratch8.resize(count * 8);
    scratchw.resize(count * win.width);
    detail8(x, m, count, scratch8.data());
    const std::uint32_t M = std::min(candidates, s8.size());
    if (M <= 1) {
      s8.nearest(scratch8.data(), count, i8);
      after_d8(x, m, i8, count, scratchw.data());
      sw.nearest(scratchw.data(), count, iw);
      return;
    }
    // M-search: the nearest D8 entry in block-mean space need not give the least total
    // error once D_W is added (a jump one step off); try the M nearest and keep the best pair.
    thread_local std::vector<std::uint8_t> cand, try8, tryw;
    thread_local std::vector<float> dist, best;
    cand.resize(count * M);
    try8.resize(count);
    tryw.resize(count);
    dist.resize(count);
    best.assign(count, std::numeric_limits<float>::infinity());
    s8.nearest_m(scratch8.data(), count, M, cand.data());
    for (std::uint32_t j = 0; j < M; ++j) {
      for (std::uint64_t i = 0; i < count; ++i) try8[i] = cand[i * M + j];
      after_d8(x, m, try8.data(), count, scratchw.data());
      sw.nearest(scratchw.data(), count, tryw.data(), dist.data());
      for (std::uint64_t i = 0; i < count; ++i)
        if (dist[i] < best[i]) best[i] = dist[i], i8[i] = try8[i], iw[i] = tryw[i];
    }
  }
};

// Shift-aligned VQ (PageMethod::vq_aligned): each vertex-window is placed in a frame of
// 2W-1 positions so that its largest step-to-step change falls at position W-1, and the
// value just before that change (its level) is removed. A front reaching every vertex at
// a different step then gives the same aligned shape everywhere, which one codebook entry
// covers instead of one entry per arrival step.
struct AlignedStage {
  std::uint32_t dim = 0;  // 2W - 1
  std::vector<std::uint8_t> shift;
  std::vector<std::uint16_t> level_q;
  std::vector<float> level_deq;
  float level_lo = 0, level_scale = 0;
  std::vector<float> ca;
  std::vector<std::uint16_t> ca_q;
  float ca_lo = 0, ca_scale = 0;
  std::vector<std::uint8_t> sample_index;
  double sample_mse = 0, train_seconds = 0;

  // Largest |x[t] - x[t-1]| (first of equals) gives the shift; the value before it the level.
  static std::uint32_t largest_change(const float* x, std::uint32_t n) {
    std::uint32_t best = 0;
    float best_change = -1.f;
    for (std::uint32_t t = 1; t < n; ++t) {
      const float change = std::fabs(x[t] - x[t - 1]);
      if (change > best_change) best_change = change, best = t;
    }
    return best;
  }

  void prepare(const Window& win, std::uint64_t N) {
    const std::uint32_t W = win.width, n = win.steps;
    dim = 2 * W - 1;
    shift.resize(N);
    std::vector<float> level(N);
    parallel_for(N, kGroup * 8, [&](std::size_t b, std::size_t e) {
      std::vector<float> x((e - b) * W);
      win.gather(b, e - b, x.data());
      for (std::size_t v = b; v < e; ++v) {
        const float* xv = x.data() + (v - b) * W;
        const std::uint32_t s = largest_change(xv, n);
        shift[v] = std::uint8_t(s);
        level[v] = xv[s > 0 ? s - 1 : 0];
      }
    });
    const auto [lo, hi] = std::minmax_element(level.begin(), level.end());
    level_lo = *lo;
    level_scale = float((double(*hi) - double(*lo)) / 65535.0);
    level_q.resize(N);
    level_deq.resize(N);
    for (std::uint64_t v = 0; v < N; ++v) {
      const double q = level_scale > 0 ? std::nearbyint((double(level[v]) - level_lo) / level_scale) : 0.0;
      level_q[v] = std::uint16_t(std::clamp(q, 0.0, 65535.0));
      level_deq[v] = detail::dequantise_mean(level_lo, level_scale, level_q[v]);
    }
  }

  // Frames of `count` vertices (x: their padded series, count x W) starting at vertex `first`.
  void frame(const float* x, const std::uint64_t* vertices, std::uint64_t first, std::uint64_t count,
             std::uint32_t W, std::uint32_t n, std::vector<float>& u, std::vector<std::uint32_t>& offsets) const {
    u.assign(count * dim, 0.f);
    offsets.resize(count);
    for (std::uint64_t i = 0; i < count; ++i) {
      const std::uint64_t v = vertices ? vertices[i] : first + i;
      const std::uint32_t a = detail::aligned_frame_start(W, shift[v]);
      offsets[i] = a;
      for (std::uint32_t t = 0; t < n; ++t) u[i * dim + a + t] = x[i * W + t] - level_deq[v];
    }
  }
  void frame(const float* x, std::uint64_t first, std::uint64_t count, std::uint32_t W, std::uint32_t n,
             std::vector<float>& u, std::vector<std::uint32_t>& offsets) const {
    frame(x, nullptr, first, count, W, n, u, offsets);
  }

  void train(const Window& win, const float* xs, const std::vector<std::uint64_t>& sample, std::uint32_t K,
             const CodecParams& params, const std::vector<float>* init) {
    const auto start = std::chrono::steady_clock::now();
    const std::uint32_t W = win.width, n = win.steps;
    const std::uint64_t S = sample.size();
    std::vector<float> u;
    std::vector<std::uint32_t> offsets;
    frame(xs, sample.data(), 0, S, W, n, u, offsets);
    const detail::PartialVectors set{u.data(), offsets.data(), S, dim, n};
    // Trained on every second sample vertex (still stratified) and scored on all of them:
    // half the training time for 0.35 dB on the shock field (65.08 -> 64.73 dB).
    constexpr std::uint64_t stride = 2;
    std::vector<float> u_train;
    std::vector<std::uint32_t> offsets_train;
    for (std::uint64_t i = 0; i < S; i += stride) {
      u_train.insert(u_train.end(), u.begin() + i * dim, u.begin() + (i + 1) * dim);
      offsets_train.push_back(offsets[i]);
    }
    const detail::PartialVectors train_set{u_train.data(), offsets_train.data(), offsets_train.size(), dim, n};
    // Half the splitting iterations of the plain codebooks: aligned vectors converge faster
    // (on the shock field 8 and 3 iterations per split give the same PSNR within 0.05 dB),
    // and this codebook is trained on top of the plain ones.
    const std::vector<float> trained =
        detail::train_lbg_partial(train_set, K, std::max(2u, params.cold_iterations / 2), params.warm_iterations, params.seed + 2, init);
    // Stored in 16 bits over the codebook's range; encoding uses the stored values.
    const auto [lo, hi] = std::minmax_element(trained.begin(), trained.end());
    ca_lo = *lo;
    ca_scale = float((double(*hi) - double(*lo)) / 65535.0);
    ca_q.resize(trained.size());
    ca.resize(trained.size());
    for (std::size_t i = 0; i < trained.size(); ++i) {
      const double q = ca_scale > 0 ? std::nearbyint((double(trained[i]) - ca_lo) / ca_scale) : 0.0;
      ca_q[i] = std::uint16_t(std::clamp(q, 0.0, 65535.0));
      ca[i] = detail::dequantise_mean(ca_lo, ca_scale, ca_q[i]);
    }
    const detail::PartialNearest search(ca.data(), K, dim, n);
    sample_index.resize(S);
    std::vector<float> dist(S);
    parallel_for(S, 512, [&](std::size_t b, std::size_t e) {
      search.nearest(set, b, e - b, sample_index.data() + b, dist.data() + b);
    });
    double total = 0;
    for (float d : dist) total += d;
    sample_mse = total / (double(S) * n);
    train_seconds = seconds_since(start);
  }
};

// What one vertex's section costs and its 4-bit code.
struct Coded {
  std::uint32_t code;
  std::uint64_t bits;
};

Coded write_raw(const float* x, std::uint32_t steps, BitWriter* writer) {
  if (writer)
    for (std::uint32_t t = 0; t < steps; ++t) writer->put(detail::float_bits(x[t]), 32);
  return {BitBlocks::kRawWidth, 32ull * steps};
}

// Quantised residual of one vertex against its VQ base (vertex_section.h). Writes nothing
// when writer is null (cost estimate only).
Coded encode_residual(const float* x, std::uint32_t steps, const float* base, float step, float bound,
                      BitWriter* writer, std::uint32_t* z) {
  for (std::uint32_t t = 0; t < steps; ++t) {
    const double q = detail::round_to_integer((double(x[t]) - base[t]) / step);
    if (!(std::fabs(q) < double(1 << 20))) return write_raw(x, steps, writer);
    const float rebuilt = base[t] + float(q) * step;
    if (std::fabs(double(x[t]) - double(rebuilt)) > bound) return write_raw(x, steps, writer);
    z[t] = detail::zigzag(std::int32_t(q));
  }
  const detail::ValueLayout layout = detail::choose_layout(z, steps);
  if (layout.code == BitBlocks::kRawWidth) return write_raw(x, steps, writer);
  if (writer) detail::write_values(*writer, z, steps, layout);
  return {layout.code, layout.bits};
}

/// The per-vertex records of a VQ page: encode_group(first, last, x) chooses the codewords of
/// vertices [first, last) (x: scratch for their windows, left holding them). With a residual,
/// each vertex's window is then coded against base(v, out), its decoded series, in bit blocks.
template <class EncodeGroup, class Base>
void encode_vertices(EncodedPage& page, std::uint64_t N, std::uint32_t W, std::uint32_t n, bool residual, float step,
                     float bound, const EncodeGroup& encode_group, const Base& base) {
  if (!residual) {
    parallel_for(N, kGroup, [&](std::size_t b, std::size_t e) {
      thread_local std::vector<float> x;
      for (std::size_t g = b; g < e; g += kGroup) encode_group(g, std::min<std::uint64_t>(e, g + kGroup), x);
    });
    return;
  }
  page.step = step;
  page.blocks = detail::build_bit_blocks(N, [&](std::uint64_t first, std::uint64_t last, const auto& run) {
    thread_local std::vector<float> x, vbase;
    thread_local std::vector<std::uint32_t> scratch;
    encode_group(first, last, x);
    vbase.resize(W);
    scratch.resize(W);
    run([&](std::uint64_t v, BitWriter& writer) {
      base(v, vbase.data());
      return encode_residual(x.data() + (v - first) * W, n, vbase.data(), step, bound, &writer, scratch.data()).code;
    });
  });
}

// Error-bounded predictive coding of one vertex: k_t = round((x - lo) / step), stored as k_0
// and the zigzag prediction errors of whichever predictor packs smaller (predictive_layout.h).
Coded encode_predictive(const float* x, std::uint32_t steps, float lo, float step, float bound,
                        std::uint32_t first_width, BitWriter* writer, std::int64_t* k, std::uint32_t* z) {
  for (std::uint32_t t = 0; t < steps; ++t) {
    const double kd = detail::round_to_integer((double(x[t]) - lo) / step);
    const float rebuilt = lo + float(kd) * step;
    if (!(kd >= 0 && kd < double(1ull << first_width)) || std::fabs(double(x[t]) - double(rebuilt)) > bound)
      return write_raw(x, steps, writer);
    k[t] = std::int64_t(kd);
  }
  const std::uint32_t count = steps - 1;
  detail::ValueLayout best;
  best.code = BitBlocks::kRawWidth;
  best.bits = ~0ull;
  std::uint32_t best_predictor = 0;
  for (std::uint32_t predictor = 0; predictor < 2; ++predictor) {
    bool fits = true;
    for (std::uint32_t t = 1; t < steps && fits; ++t) {
      const std::int64_t d = k[t] - detail::predict(predictor, t, k[t - 1], t >= 2 ? k[t - 2] : 0);
      fits = d < (1 << 20) && d > -(1 << 20);
      z[t - 1] = fits ? detail::zigzag(std::int32_t(d)) : 0;
    }
    if (!fits) continue;
    const detail::ValueLayout layout = detail::choose_layout(z, count);
    if (layout.code != BitBlocks::kRawWidth && layout.bits < best.bits) best = layout, best_predictor = predictor;
  }
  if (best.code == BitBlocks::kRawWidth) return write_raw(x, steps, writer);
  if (writer) {
    for (std::uint32_t t = 1; t < steps; ++t)
      z[t - 1] = detail::zigzag(
          std::int32_t(k[t] - detail::predict(best_predictor, t, k[t - 1], t >= 2 ? k[t - 2] : 0)));
    writer->put(best_predictor, 1);
    writer->put(std::uint32_t(k[0]), first_width);
    detail::write_values(*writer, z, count, best);
  }
  return {best.code, 1 + first_width + best.bits};
}

}  // namespace

double resolve_bound(const ErrorBound& bound, double value_min, double value_max) {
  switch (bound.kind) {
    case BoundKind::none:
      return 0;
    case BoundKind::absolute:
      return bound.value;
    case BoundKind::range_relative: {
      // Halves first: the range of values near DBL_MAX overflows.
      const double b = 2 * bound.value * (value_max / 2 - value_min / 2);
      // A constant field has no range; hold it (nearly) exactly rather than not at all.
      return std::max(b, std::numeric_limits<double>::denorm_min());
    }
  }
  return 0;
}

EncodedPage encode_window(const float* steps, std::uint64_t vertex_count, std::uint32_t step_count,
                          const double* times, std::uint64_t first_step, const CodecParams& params, float bound_abs,
                          WarmStart* warm, WindowStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  const std::uint32_t W = params.window, K = params.codebook_size;
  require(steps != nullptr && times != nullptr, "encode_window: null data or times");
  require(vertex_count >= 1, "encode_window: vertex_count must be positive");
  require(detail::valid_window(W),
          "encode_window: window must be a multiple of 8 in [8, 1024], got " + std::to_string(W));
  require(detail::valid_codebook_size(K), "encode_window: codebook_size must be 2..256, got " + std::to_string(K));
  require(step_count >= 1 && step_count <= W, "encode_window: step_count must be 1..window, got " +
                                                  std::to_string(step_count));
  require(std::isfinite(bound_abs) && bound_abs >= 0.f,
          "encode_window: bound must be finite and >= 0, got " + std::to_string(bound_abs));
  require(params.training_sample >= 1, "encode_window: training_sample must be positive");
  const std::uint64_t N = vertex_count;
  const std::uint32_t n = step_count;
  const Window win{steps, N, n, W, W / 8};

  // Non-finite values, value range and per-vertex means (of the padded series), in parallel.
  constexpr std::uint64_t kChunk = 4096;
  const std::uint64_t chunks = (N + kChunk - 1) / kChunk;
  std::vector<float> cmin(chunks, std::numeric_limits<float>::infinity());
  std::vector<float> cmax(chunks, -std::numeric_limits<float>::infinity());
  std::vector<std::uint64_t> bad(chunks, ~0ull);  // first non-finite as t * N + v
  std::vector<double> mean(N);
  parallel_for(N, kChunk, [&](std::size_t b, std::size_t e) {
    const std::uint64_t c = b / kChunk;
    std::vector<double> sum(e - b, 0.0);
    // Locals, stored once: the threads' entries of cmin, cmax and bad share cache lines.
    float lo = cmin[c], hi = cmax[c];
    std::uint64_t first_bad = bad[c];
    for (std::uint32_t t = 0; t < n; ++t) {
      const float* row = steps + std::uint64_t(t) * N;
      const double weight = t + 1 == n ? double(W - n + 1) : 1.0;
      for (std::size_t v = b; v < e; ++v) {
        const float x = row[v];
        if (!std::isfinite(x)) {
          first_bad = std::min<std::uint64_t>(first_bad, std::uint64_t(t) * N + v);
          continue;
        }
        lo = std::min(lo, x);
        hi = std::max(hi, x);
        sum[v - b] += weight * x;
      }
    }
    cmin[c] = lo;
    cmax[c] = hi;
    bad[c] = first_bad;
    for (std::size_t v = b; v < e; ++v) mean[v] = sum[v - b] / W;
  });
  const std::uint64_t first_bad = *std::min_element(bad.begin(), bad.end());
  if (first_bad != ~0ull) {
    const std::uint64_t t = first_bad / N, v = first_bad % N;
    throw Error(ErrorCode::invalid_argument, "encode_window: value at step " + std::to_string(first_step + t) +
                                                 ", vertex " + std::to_string(v) + " is " +
                                                 (std::isnan(steps[first_bad]) ? "NaN" : "infinite") +
                                                 "; compressed fields must be finite");
  }

  EncodedPage page;
  page.first_step = first_step;
  page.step_count = n;
  page.window = W;
  page.codebook_size = K;
  page.vertex_count = N;
  page.times.assign(times, times + n);
  page.value_min = *std::min_element(cmin.begin(), cmin.end());
  page.value_max = *std::max_element(cmax.begin(), cmax.end());

  // 16-bit mean over the window's range of means.
  const auto [mlo, mhi] = std::minmax_element(mean.begin(), mean.end());
  page.mean_lo = float(*mlo);
  page.mean_scale = float((*mhi - *mlo) / 65535.0);
  page.mean_q.resize(N);
  std::vector<float> mean_deq(N);
  for (std::uint64_t v = 0; v < N; ++v) {
    const double q = page.mean_scale > 0 ? std::nearbyint((mean[v] - page.mean_lo) / page.mean_scale) : 0.0;
    page.mean_q[v] = std::uint16_t(std::clamp(q, 0.0, 65535.0));
    mean_deq[v] = detail::dequantise_mean(page.mean_lo, page.mean_scale, page.mean_q[v]);
  }

  // Stratified training sample: one vertex from each of S equal strata.
  const std::uint64_t S = std::min<std::uint64_t>(N, params.training_sample);
  std::vector<std::uint64_t> sample(S);
  std::uint64_t rng = params.seed ^ (first_step * 0x2545f4914f6cdd1dull);
  for (std::uint64_t i = 0; i < S; ++i) {
    const double u = S == N ? 0.0 : double(detail::splitmix(rng) >> 11) * 0x1.0p-53;
    sample[i] = std::min<std::uint64_t>(N - 1, std::uint64_t((double(i) + u) * double(N) / double(S)));
  }
  std::vector<float> xs(S * W), ms(S);
  for (std::uint64_t i = 0; i < S; ++i) {
    win.gather(sample[i], 1, xs.data() + i * W);
    ms[i] = mean_deq[sample[i]];
  }

  // Codebooks: D8 on the sample, then D_W on what the decoded D8 leaves (closed loop).
  const auto train_start = std::chrono::steady_clock::now();
  const bool warm_ok = warm && warm->c8.size() == std::size_t(K) * 8 && warm->cw.size() == std::size_t(K) * W;
  std::vector<float> d8s(S * 8), rs(S * W);
  block_means(win, xs.data(), ms.data(), S, d8s.data());
  std::vector<std::uint8_t> i8s(S), iws(S);
  // Trains both codebooks (warm from `warm` if given) into page.c8/cw, assigns the sample,
  // and returns VQ's mean squared error per real value on it.
  auto train_plain = [&](const WarmStart* from) {
    LbgOptions lbg{K, params.cold_iterations, params.warm_iterations, params.seed};
    page.c8 = train_lbg(d8s.data(), S, 8, lbg, from ? &from->c8 : nullptr);
    NearestSearch(page.c8.data(), K, 8).nearest(d8s.data(), S, i8s.data());
    remove_d8(win, page.c8, xs.data(), ms.data(), i8s.data(), S, rs.data());
    lbg.seed = params.seed + 1;
    page.cw = train_lbg(rs.data(), S, W, lbg, from ? &from->cw : nullptr);
    NearestSearch(page.cw.data(), K, W).nearest(rs.data(), S, iws.data());
    double err = 0;
    std::vector<float> series(W);
    for (std::uint64_t i = 0; i < S; ++i) {
      detail::vq_series(ms[i], page.c8.data() + std::size_t(i8s[i]) * 8, page.cw.data() + std::size_t(iws[i]) * W,
                        W, series.data());
      for (std::uint32_t t = 0; t < n; ++t) err += (double(xs[i * W + t]) - series[t]) * (double(xs[i * W + t]) - series[t]);
    }
    return err / (double(S) * n);
  };
  double plain_mse = train_plain(warm_ok ? warm : nullptr);
  double train_seconds = seconds_since(train_start);

  // Variance of the sample (real steps only), for VQ's signal-to-noise ratio.
  double sum = 0, sum2 = 0;
  for (std::uint64_t i = 0; i < S; ++i)
    for (std::uint32_t t = 0; t < n; ++t) {
      const double x = xs[i * W + t];
      sum += x;
      sum2 += x * x;
    }
  const double count = double(S) * n;
  const double variance = std::max(0.0, sum2 / count - (sum / count) * (sum / count));

  // Shift-aligned alternative: trained on the same sample, kept if it fits the sample better.
  AlignedStage aligned;
  // Shifts are stored in one byte: windows up to 256 steps.
  const bool try_aligned = params.aligned && W <= detail::kMaxAlignedWindow && n >= 2 && plain_mse > 0;
  const bool warm_aligned = try_aligned && warm_ok && warm->ca.size() == std::size_t(K) * (2 * W - 1);
  if (try_aligned) {
    aligned.prepare(win, N);
    aligned.train(win, xs.data(), sample, K, params, warm_aligned ? &warm->ca : nullptr);
  }

  // A warm start only refines the previous window's entries; when the field changed kind (a
  // transient, a front that swept in and left tails behind), they stay where the old data
  // was and Lloyd iterations do not move them far. Then the kind of codebook the previous
  // page used is also trained cold, and the better codebooks kept (shock field: plain VQ
  // 38.7 -> 45 dB, aligned 46 -> 65 dB). One kind only: a second cold training would double
  // the cost of such a window.
  const bool aligned_leads = try_aligned && (warm_ok ? warm->aligned_page : aligned.sample_mse < plain_mse);
  if (aligned_leads && warm_aligned && aligned.sample_mse > 2.0 * warm->ca_mse) {
    AlignedStage cold = aligned;
    cold.train(win, xs.data(), sample, K, params, nullptr);
    cold.train_seconds += aligned.train_seconds;
    if (cold.sample_mse < aligned.sample_mse) aligned = std::move(cold);
    else aligned.train_seconds = cold.train_seconds;
  } else if (!aligned_leads && warm_ok && plain_mse > 2.0 * warm->vq_mse) {
    const auto cold_start = std::chrono::steady_clock::now();
    const std::vector<float> warm_c8 = page.c8, warm_cw = page.cw;
    const std::vector<std::uint8_t> warm_i8 = i8s, warm_iw = iws;
    const double cold_mse = train_plain(nullptr);
    if (cold_mse < plain_mse) {
      plain_mse = cold_mse;
    } else {
      page.c8 = warm_c8;
      page.cw = warm_cw;
      i8s = warm_i8;
      iws = warm_iw;
    }
    train_seconds += seconds_since(cold_start);
  }
  if (warm) {
    warm->c8 = page.c8;
    warm->cw = page.cw;
    warm->vq_mse = plain_mse;
    if (try_aligned) warm->ca = aligned.ca, warm->ca_mse = aligned.sample_mse;
    else warm->ca.clear();
  }
  double vq_mse = plain_mse;
  std::vector<float> base(W);
  const bool use_aligned = try_aligned && aligned.sample_mse < vq_mse;
  if (use_aligned) vq_mse = aligned.sample_mse;
  if (warm) warm->aligned_page = use_aligned;
  // The VQ value of sample vertex i at its W steps (whichever VQ the page uses).
  auto sample_base = [&](std::uint64_t i, float* out) {
    if (use_aligned)
      detail::aligned_series(aligned.level_deq[sample[i]], aligned.ca.data() + std::size_t(aligned.sample_index[i]) * aligned.dim,
                             W, aligned.shift[sample[i]], n, out);
    else
      detail::vq_series(ms[i], page.c8.data() + std::size_t(i8s[i]) * 8, page.cw.data() + std::size_t(iws[i]) * W,
                        W, out);
  };
  const double snr_db = vq_mse > 0 ? 10.0 * std::log10(std::max(variance, 1e-300) / vq_mse) : 300.0;

  float bound = bound_abs;
  PageMethod method = bound > 0 ? PageMethod::vq_residual : PageMethod::vq;
  if (bound == 0 && snr_db < params.min_vq_snr_db && vq_mse > 0) {
    // VQ-poor and unbounded: a predictive coder at VQ's own RMS error is never less accurate.
    bound = float(std::sqrt(vq_mse));
    method = PageMethod::predictive;
  }
  const double codebook_bytes = use_aligned ? double(K) * aligned.dim * 2 : double(K) * (8 + W) * 4;
  const double vq_base_bytes = double(N) * 4 + codebook_bytes;
  double vq_estimate = vq_base_bytes, predictive_estimate = 0;
  const float step = 2.f * bound;
  const float lo = page.value_min;
  std::uint32_t first_width = 0;
  if (bound > 0) {
    const double levels = std::ceil((double(page.value_max) - lo) / step) + 1;
    first_width = levels >= double(1u << 30) ? 31u : std::max(1u, detail::bit_width(std::uint32_t(levels)));
    std::vector<std::uint32_t> z(W);
    std::vector<std::int64_t> k(W);
    double vq_bits = 0, pred_bits = 0;
    for (std::uint64_t i = 0; i < S; ++i) {
      const float* x = xs.data() + i * W;
      sample_base(i, base.data());
      vq_bits += double(encode_residual(x, n, base.data(), step, bound, nullptr, z.data()).bits);
      pred_bits += double(encode_predictive(x, n, lo, step, bound, first_width, nullptr, k.data(), z.data()).bits);
    }
    const double per_vertex_overhead = 0.5 + 8.0 / kGroup;  // width nibble + group offset
    vq_estimate += double(N) * (per_vertex_overhead + vq_bits / double(S) / 8);
    predictive_estimate = double(N) * (per_vertex_overhead + pred_bits / double(S) / 8);
    if (method == PageMethod::vq_residual && predictive_estimate < vq_estimate) method = PageMethod::predictive;
  }
  // The estimate above is of per-vertex sections; lane blocks come out smaller where a run's
  // first steps jump (their first step has a width of its own) and about the same elsewhere.
  if (method == PageMethod::predictive && params.predictive_lanes) method = PageMethod::predictive_lanes;
  if (use_aligned && method == PageMethod::vq) method = PageMethod::vq_aligned;
  if (use_aligned && method == PageMethod::vq_residual) method = PageMethod::vq_aligned_residual;
  page.method = method;
  page.bound = method == PageMethod::vq || method == PageMethod::vq_aligned ? 0.f : bound;
  page.sample_snr_db = float(std::min(snr_db, 1e30));
  page.vq_bytes_estimate = float(vq_estimate);
  page.predictive_bytes_estimate = float(predictive_estimate);
  const bool residual = method == PageMethod::vq_residual || method == PageMethod::vq_aligned_residual;

  if (method == PageMethod::predictive || method == PageMethod::predictive_lanes) {
    page.step = step;
    page.lo = lo;
    page.first_width = first_width;
    page.c8.clear();
    page.cw.clear();
    page.mean_q.clear();
    page.mean_lo = page.mean_scale = 0;
    if (method == PageMethod::predictive_lanes) {
      page.lanes = detail::build_lane_blocks(N, n, W, lo, step, bound, first_width,
                                             [&](std::uint64_t first, std::uint64_t count, float* x) { win.gather(first, count, x); });
      const std::string error = detail::lane_blocks_error(page, &page.lanes);
      if (!error.empty()) throw Error(ErrorCode::internal_error, "encode_window: lane blocks: " + error);
    } else {
      page.blocks = detail::build_bit_blocks(N, [&](std::uint64_t first, std::uint64_t last, const auto& run) {
        thread_local std::vector<float> x;
        thread_local std::vector<std::int64_t> k;
        thread_local std::vector<std::uint32_t> z;
        x.resize((last - first) * W);
        k.resize(W);
        z.resize(W);
        win.gather(first, last - first, x.data());
        run([&](std::uint64_t v, BitWriter& writer) {
          return encode_predictive(x.data() + (v - first) * W, n, lo, step, bound, first_width, &writer, k.data(),
                                   z.data())
              .code;
        });
      });
    }
  } else if (use_aligned) {
    page.c8.clear();
    page.cw.clear();
    page.mean_q = aligned.level_q;
    page.mean_lo = aligned.level_lo;
    page.mean_scale = aligned.level_scale;
    page.ca = aligned.ca;
    page.ca_q = aligned.ca_q;
    page.ca_lo = aligned.ca_lo;
    page.ca_scale = aligned.ca_scale;
    page.shift = aligned.shift;
    page.ia.resize(N);
    const detail::PartialNearest search(page.ca.data(), K, aligned.dim, n);
    auto encode_group = [&](std::uint64_t first, std::uint64_t last, std::vector<float>& x) {
      thread_local std::vector<float> u;
      thread_local std::vector<std::uint32_t> offsets;
      x.resize((last - first) * W);
      win.gather(first, last - first, x.data());
      aligned.frame(x.data(), first, last - first, W, n, u, offsets);
      const detail::PartialVectors set{u.data(), offsets.data(), last - first, aligned.dim, n};
      search.nearest(set, 0, last - first, page.ia.data() + first);
    };
    encode_vertices(page, N, W, n, residual, step, bound, encode_group, [&](std::uint64_t v, float* out) {
      detail::aligned_series(aligned.level_deq[v], page.ca.data() + std::size_t(page.ia[v]) * aligned.dim, W,
                             page.shift[v], n, out);
    });
  } else {
    page.i8.resize(N);
    page.iw.resize(N);
    const std::vector<float>& mean_f = mean_deq;
    const NearestSearch s8(page.c8.data(), K, 8);
    const NearestSearch sw(page.cw.data(), K, W);
    const VqStage stage{win, mean_f, page.c8, page.cw, s8, sw, params.search_candidates};
    auto encode_group = [&](std::uint64_t first, std::uint64_t last, std::vector<float>& x) {
      thread_local std::vector<float> scratch8, scratchw;
      x.resize((last - first) * W);
      win.gather(first, last - first, x.data());
      stage.encode(x.data(), mean_f.data() + first, last - first, page.i8.data() + first, page.iw.data() + first,
                   scratch8, scratchw);
    };
    encode_vertices(page, N, W, n, residual, step, bound, encode_group, [&](std::uint64_t v, float* out) {
      detail::vq_series(mean_f[v], page.c8.data() + std::size_t(page.i8[v]) * 8,
                        page.cw.data() + std::size_t(page.iw[v]) * W, W, out);
    });
  }

  if (stats) {
    stats->train_seconds = train_seconds + aligned.train_seconds;
    stats->sample_snr_db = snr_db;
    stats->vq_bytes_estimate = std::uint64_t(vq_estimate);
    stats->predictive_bytes_estimate = std::uint64_t(predictive_estimate);
    stats->encode_seconds = seconds_since(start);
  }
  return page;
}

}  // namespace penumbra::compression
