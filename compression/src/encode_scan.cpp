// SPDX-License-Identifier: BSD-3-Clause
// compression/src/encode_scan.cpp -- the window's one pass over all values (range, non-finite
// values, means) and the training sample drawn from it.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "encode_stages.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "splitmix.h"

namespace penumbra::compression::detail {

namespace {

/// What one chunk of vertices holds; each thread fills its own.
struct ChunkScan {
  float lo = std::numeric_limits<float>::infinity();
  float hi = -std::numeric_limits<float>::infinity();
  std::uint64_t first_bad = ~0ull;  ///< first non-finite value as t * N + v
};

/// Scans vertices [b, e) and stores their means (weighted so that the last real step stands for
/// the padding that repeats it).
ChunkScan scan_chunk(const Window& win, std::size_t b, std::size_t e, std::vector<double>& mean) {
  const std::uint64_t N = win.n_vertices;
  const std::uint32_t n = win.steps, W = win.width;
  ChunkScan c;
  std::vector<double> sum(e - b, 0.0);
  for (std::uint32_t t = 0; t < n; ++t) {
    const float* row = win.data + std::uint64_t(t) * N;
    const double weight = t + 1 == n ? double(W - n + 1) : 1.0;
    for (std::size_t v = b; v < e; ++v) {
      const float x = row[v];
      if (!std::isfinite(x)) {
        c.first_bad = std::min<std::uint64_t>(c.first_bad, std::uint64_t(t) * N + v);
        continue;
      }
      c.lo = std::min(c.lo, x);
      c.hi = std::max(c.hi, x);
      sum[v - b] += weight * x;
    }
  }
  for (std::size_t v = b; v < e; ++v) mean[v] = sum[v - b] / W;
  return c;
}

[[noreturn]] void throw_non_finite(const Window& win, std::uint64_t first_bad, std::uint64_t first_step) {
  const std::uint64_t t = first_bad / win.n_vertices, v = first_bad % win.n_vertices;
  throw Error(ErrorCode::invalid_argument, "encode_window: value at step " + std::to_string(first_step + t) +
                                               ", vertex " + std::to_string(v) + " is " +
                                               (std::isnan(win.data[first_bad]) ? "NaN" : "infinite") +
                                               "; compressed fields must be finite");
}

}  // namespace

WindowScan scan_window(const Window& win, std::uint64_t first_step) {
  constexpr std::uint64_t kChunk = 4096;
  const std::uint64_t N = win.n_vertices;
  std::vector<ChunkScan> chunks((N + kChunk - 1) / kChunk);
  WindowScan scan;
  scan.mean.resize(N);
  parallel_for(N, kChunk, [&](std::size_t b, std::size_t e) { chunks[b / kChunk] = scan_chunk(win, b, e, scan.mean); });
  std::uint64_t first_bad = ~0ull;
  scan.value_min = std::numeric_limits<float>::infinity();
  scan.value_max = -std::numeric_limits<float>::infinity();
  for (const ChunkScan& c : chunks) {
    first_bad = std::min(first_bad, c.first_bad);
    scan.value_min = std::min(scan.value_min, c.lo);
    scan.value_max = std::max(scan.value_max, c.hi);
  }
  if (first_bad != ~0ull) throw_non_finite(win, first_bad, first_step);
  return scan;
}

TrainingSample draw_training_sample(const Window& win, const std::vector<float>& mean, const CodecParams& params,
                                    std::uint64_t first_step) {
  const std::uint64_t N = win.n_vertices, S = std::min<std::uint64_t>(N, params.training_sample);
  const std::uint32_t W = win.width;
  TrainingSample sample;
  sample.vertices.resize(S);
  std::uint64_t rng = params.seed ^ (first_step * 0x2545f4914f6cdd1dull);
  for (std::uint64_t i = 0; i < S; ++i) {
    const double u = S == N ? 0.0 : double(splitmix(rng) >> 11) * 0x1.0p-53;
    sample.vertices[i] = std::min<std::uint64_t>(N - 1, std::uint64_t((double(i) + u) * double(N) / double(S)));
  }
  sample.series.resize(S * W);
  sample.means.resize(S);
  for (std::uint64_t i = 0; i < S; ++i) {
    win.gather(sample.vertices[i], 1, sample.series.data() + i * W);
    sample.means[i] = mean[sample.vertices[i]];
  }
  return sample;
}

}  // namespace penumbra::compression::detail
