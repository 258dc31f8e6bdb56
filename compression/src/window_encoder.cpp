// compression/src/window_encoder.cpp -- encodes one window: VQ (mean + D8 + D_W, closed loop),
// optional quantised residual, or the error-bounded predictive coder for VQ-poor windows.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "bit_blocks_builder.h"
#include "bit_io.h"
#include "predictive_layout.h"
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

std::uint64_t splitmix(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
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
    const double q = std::nearbyint((double(x[t]) - base[t]) / step);
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

// Error-bounded predictive coding of one vertex: k_t = round((x - lo) / step), stored as k_0
// and the zigzag prediction errors of whichever predictor packs smaller (predictive_layout.h).
Coded encode_predictive(const float* x, std::uint32_t steps, float lo, float step, float bound,
                        std::uint32_t first_width, BitWriter* writer, std::int64_t* k, std::uint32_t* z) {
  for (std::uint32_t t = 0; t < steps; ++t) {
    const double kd = std::nearbyint((double(x[t]) - lo) / step);
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

float resolve_bound(const ErrorBound& bound, float value_min, float value_max) {
  switch (bound.kind) {
    case BoundKind::none:
      return 0.f;
    case BoundKind::absolute:
      return float(bound.value);
    case BoundKind::range_relative: {
      const double b = bound.value * (double(value_max) - double(value_min));
      // A constant field has no range; hold it (nearly) exactly rather than not at all.
      return float(std::max(b, double(std::numeric_limits<float>::min())));
    }
  }
  return 0.f;
}

EncodedPage encode_window(const float* steps, std::uint64_t vertex_count, std::uint32_t step_count,
                          const double* times, std::uint64_t first_step, const CodecParams& params, float bound_abs,
                          WarmStart* warm, WindowStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  const std::uint32_t W = params.window, K = params.codebook_size;
  require(steps != nullptr && times != nullptr, "encode_window: null data or times");
  require(vertex_count >= 1, "encode_window: vertex_count must be positive");
  require(W >= 8 && W <= 1024 && W % 8 == 0,
          "encode_window: window must be a multiple of 8 in [8, 1024], got " + std::to_string(W));
  require(K >= 2 && K <= 256, "encode_window: codebook_size must be 2..256, got " + std::to_string(K));
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
    for (std::uint32_t t = 0; t < n; ++t) {
      const float* row = steps + std::uint64_t(t) * N;
      const double weight = t + 1 == n ? double(W - n + 1) : 1.0;
      for (std::size_t v = b; v < e; ++v) {
        const float x = row[v];
        if (!std::isfinite(x)) {
          bad[c] = std::min<std::uint64_t>(bad[c], std::uint64_t(t) * N + v);
          continue;
        }
        cmin[c] = std::min(cmin[c], x);
        cmax[c] = std::max(cmax[c], x);
        sum[v - b] += weight * x;
      }
    }
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
    const double u = S == N ? 0.0 : double(splitmix(rng) >> 11) * 0x1.0p-53;
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
  LbgOptions lbg{K, params.cold_iterations, params.warm_iterations, params.seed};
  std::vector<float> d8s(S * 8);
  block_means(win, xs.data(), ms.data(), S, d8s.data());
  page.c8 = train_lbg(d8s.data(), S, 8, lbg, warm_ok ? &warm->c8 : nullptr);
  const NearestSearch s8(page.c8.data(), K, 8);
  std::vector<std::uint8_t> i8s(S), iws(S);
  s8.nearest(d8s.data(), S, i8s.data());
  std::vector<float> rs(S * W);
  remove_d8(win, page.c8, xs.data(), ms.data(), i8s.data(), S, rs.data());
  lbg.seed = params.seed + 1;
  page.cw = train_lbg(rs.data(), S, W, lbg, warm_ok ? &warm->cw : nullptr);
  const NearestSearch sw(page.cw.data(), K, W);
  sw.nearest(rs.data(), S, iws.data());
  const double train_seconds = seconds_since(train_start);
  if (warm) {
    warm->c8 = page.c8;
    warm->cw = page.cw;
  }

  // How well VQ does on the sample (real steps only), and what each method would cost.
  double err2 = 0, sum = 0, sum2 = 0;
  std::vector<float> base(W);
  for (std::uint64_t i = 0; i < S; ++i) {
    detail::vq_series(ms[i], page.c8.data() + std::size_t(i8s[i]) * 8, page.cw.data() + std::size_t(iws[i]) * W, W,
                      base.data());
    for (std::uint32_t t = 0; t < n; ++t) {
      const double x = xs[i * W + t];
      err2 += (x - base[t]) * (x - base[t]);
      sum += x;
      sum2 += x * x;
    }
  }
  const double count = double(S) * n;
  const double variance = std::max(0.0, sum2 / count - (sum / count) * (sum / count));
  const double vq_mse = err2 / count;
  const double snr_db = vq_mse > 0 ? 10.0 * std::log10(std::max(variance, 1e-300) / vq_mse) : 300.0;

  float bound = bound_abs;
  PageMethod method = bound > 0 ? PageMethod::vq_residual : PageMethod::vq;
  if (bound == 0 && snr_db < params.min_vq_snr_db && vq_mse > 0) {
    // VQ-poor and unbounded: a predictive coder at VQ's own RMS error is never less accurate.
    bound = float(std::sqrt(vq_mse));
    method = PageMethod::predictive;
  }
  const double vq_base_bytes = double(N) * 4 + double(K) * (8 + W) * 4;
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
      detail::vq_series(ms[i], page.c8.data() + std::size_t(i8s[i]) * 8, page.cw.data() + std::size_t(iws[i]) * W,
                        W, base.data());
      vq_bits += double(encode_residual(x, n, base.data(), step, bound, nullptr, z.data()).bits);
      pred_bits += double(encode_predictive(x, n, lo, step, bound, first_width, nullptr, k.data(), z.data()).bits);
    }
    const double per_vertex_overhead = 0.5 + 8.0 / kGroup;  // width nibble + group offset
    vq_estimate += double(N) * (per_vertex_overhead + vq_bits / double(S) / 8);
    predictive_estimate = double(N) * (per_vertex_overhead + pred_bits / double(S) / 8);
    if (method == PageMethod::vq_residual && predictive_estimate < vq_estimate) method = PageMethod::predictive;
  }
  page.method = method;
  page.bound = method == PageMethod::vq ? 0.f : bound;
  page.sample_snr_db = float(std::min(snr_db, 1e30));
  page.vq_bytes_estimate = float(vq_estimate);
  page.predictive_bytes_estimate = float(predictive_estimate);

  if (method == PageMethod::predictive) {
    page.step = step;
    page.lo = lo;
    page.first_width = first_width;
    page.c8.clear();
    page.cw.clear();
    page.mean_q.clear();
    page.mean_lo = page.mean_scale = 0;
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
  } else {
    page.i8.resize(N);
    page.iw.resize(N);
    const std::vector<float>& mean_f = mean_deq;
    const VqStage stage{win, mean_f, page.c8, page.cw, s8, sw, params.search_candidates};
    auto encode_group = [&](std::uint64_t first, std::uint64_t last, std::vector<float>& x) {
      thread_local std::vector<float> scratch8, scratchw;
      x.resize((last - first) * W);
      win.gather(first, last - first, x.data());
      stage.encode(x.data(), mean_f.data() + first, last - first, page.i8.data() + first, page.iw.data() + first,
                   scratch8, scratchw);
    };
    if (method == PageMethod::vq) {
      parallel_for(N, kGroup, [&](std::size_t b, std::size_t e) {
        thread_local std::vector<float> x;
        for (std::size_t g = b; g < e; g += kGroup) encode_group(g, std::min<std::uint64_t>(e, g + kGroup), x);
      });
    } else {
      page.step = step;
      page.blocks = detail::build_bit_blocks(N, [&](std::uint64_t first, std::uint64_t last, const auto& run) {
        thread_local std::vector<float> x, vbase;
        thread_local std::vector<std::uint32_t> scratch;
        encode_group(first, last, x);
        vbase.resize(W);
        scratch.resize(W);
        run([&](std::uint64_t v, BitWriter& writer) {
          detail::vq_series(mean_f[v], page.c8.data() + std::size_t(page.i8[v]) * 8,
                            page.cw.data() + std::size_t(page.iw[v]) * W, W, vbase.data());
          return encode_residual(x.data() + (v - first) * W, n, vbase.data(), step, bound, &writer, scratch.data())
              .code;
        });
      });
    }
  }

  if (stats) {
    stats->train_seconds = train_seconds;
    stats->sample_snr_db = snr_db;
    stats->vq_bytes_estimate = std::uint64_t(vq_estimate);
    stats->predictive_bytes_estimate = std::uint64_t(predictive_estimate);
    stats->encode_seconds = seconds_since(start);
  }
  return page;
}

}  // namespace penumbra::compression
