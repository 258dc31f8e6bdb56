// SPDX-License-Identifier: BSD-3-Clause
// compression/src/encode_vq.cpp -- plain VQ pages (vq, vq_residual): per vertex a 16-bit mean,
// a D8 entry (means of 8 blocks) and a D_W entry (what D8 leaves), coded closed loop.
#include <limits>
#include <utility>

#include "encode_sections.h"
#include "encode_stages.h"

namespace penumbra::compression::detail {

namespace {

/// Chooses each vertex's D8 and D_W entries.
struct PlainVqSearch {
  const Window& win;
  const std::vector<float>& c8;
  const NearestSearch& s8;
  const NearestSearch& sw;
  std::uint32_t candidates;

  /// Entries for the `count` series x (count x W) with means m.
  void encode(const float* x, const float* m, std::uint64_t count, std::uint8_t* i8, std::uint8_t* iw,
              std::vector<float>& scratch8, std::vector<float>& scratchw) const {
    scratch8.resize(count * 8);
    scratchw.resize(count * win.width);
    block_means(win, x, m, count, scratch8.data());
    const std::uint32_t M = std::min(candidates, s8.size());
    if (M <= 1) {
      s8.nearest(scratch8.data(), count, i8);
      remove_d8(win, c8, x, m, i8, count, scratchw.data());
      sw.nearest(scratchw.data(), count, iw);
      return;
    }
    best_of_candidates(x, m, count, M, scratch8, scratchw, i8, iw);
  }

  // M-search: the nearest D8 entry in block-mean space need not give the least total error once
  // D_W is added (a jump one step off); try the M nearest and keep the best pair.
  void best_of_candidates(const float* x, const float* m, std::uint64_t count, std::uint32_t M,
                          const std::vector<float>& d8, std::vector<float>& scratchw, std::uint8_t* i8,
                          std::uint8_t* iw) const {
    thread_local std::vector<std::uint8_t> cand, try8, tryw;
    thread_local std::vector<float> dist, best;
    cand.resize(count * M);
    try8.resize(count);
    tryw.resize(count);
    dist.resize(count);
    best.assign(count, std::numeric_limits<float>::infinity());
    s8.nearest_m(d8.data(), count, M, cand.data());
    for (std::uint32_t j = 0; j < M; ++j) {
      for (std::uint64_t i = 0; i < count; ++i) try8[i] = cand[i * M + j];
      remove_d8(win, c8, x, m, try8.data(), count, scratchw.data());
      sw.nearest(scratchw.data(), count, tryw.data(), dist.data());
      for (std::uint64_t i = 0; i < count; ++i)
        if (dist[i] < best[i]) best[i] = dist[i], i8[i] = try8[i], iw[i] = tryw[i];
    }
  }
};

}  // namespace

void block_means(const Window& win, const float* x, const float* m, std::uint64_t count, float* d8) {
  for (std::uint64_t i = 0; i < count; ++i)
    for (std::uint32_t b = 0; b < 8; ++b) {
      double s = 0;
      for (std::uint32_t t = b * win.block; t < (b + 1) * win.block; ++t) s += double(x[i * win.width + t]) - m[i];
      d8[i * 8 + b] = float(s / win.block);
    }
}

void remove_d8(const Window& win, const std::vector<float>& c8, const float* x, const float* m,
               const std::uint8_t* i8, std::uint64_t count, float* r) {
  for (std::uint64_t i = 0; i < count; ++i) {
    const float* c = c8.data() + std::size_t(i8[i]) * 8;
    for (std::uint32_t t = 0; t < win.width; ++t) r[i * win.width + t] = x[i * win.width + t] - (m[i] + c[t / win.block]);
  }
}

void encode_vq_page(EncodedPage& page, const Window& win, const Quantised16& means, TrainedPlainCodebooks codebooks,
                    const MethodChoice& choice, std::uint32_t search_candidates) {
  const std::uint64_t N = win.n_vertices;
  const std::uint32_t W = win.width, K = page.codebook_size;
  page.means = means.stored();
  VqCodebooks& vq = page.vq;
  vq.c8 = std::move(codebooks.c8);
  vq.cw = std::move(codebooks.cw);
  vq.i8.resize(N);
  vq.iw.resize(N);
  const NearestSearch s8(vq.c8.data(), K, 8);
  const NearestSearch sw(vq.cw.data(), K, W);
  const PlainVqSearch search{win, vq.c8, s8, sw, search_candidates};
  const std::vector<float>& mean = means.values;
  auto encode_group = [&](std::uint64_t first, std::uint64_t last, std::vector<float>& x) {
    thread_local std::vector<float> scratch8, scratchw;
    x.resize((last - first) * W);
    win.gather(first, last - first, x.data());
    search.encode(x.data(), mean.data() + first, last - first, vq.i8.data() + first, vq.iw.data() + first,
                  scratch8, scratchw);
  };
  const bool residual = choice.method == PageMethod::vq_residual;
  encode_vq_vertices(page, N, W, win.steps, residual, choice.quantiser.step, choice.bound, encode_group,
                     [&](std::uint64_t v, float* out) {
                       vq_series(mean[v], vq.c8.data() + std::size_t(vq.i8[v]) * 8,
                                 vq.cw.data() + std::size_t(vq.iw[v]) * W, W, out);
                     });
}

}  // namespace penumbra::compression::detail
