// SPDX-License-Identifier: BSD-3-Clause
// compression/src/encode_training.cpp -- the window's codebooks, trained with LBG on the
// training sample: plain (D8, then D_W) and shift-aligned, warm started from the previous window.
#include <algorithm>
#include <chrono>
#include <utility>

#include "aligned_lbg.h"
#include "encode_stages.h"
#include "page_methods.h"
#include "penumbra/core/thread_pool.h"

namespace penumbra::compression::detail {

namespace {

/// Calls train() and adds the seconds it took to `seconds`.
template <class Train>
auto timed(double& seconds, const Train& train) {
  const auto start = std::chrono::steady_clock::now();
  auto result = train();
  seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

/// Mean squared error per real value of the sample against its VQ series.
double plain_sample_mse(const Window& win, const TrainingSample& sample, const TrainedPlainCodebooks& books) {
  const std::uint32_t W = win.width, n = win.steps;
  const std::uint64_t S = sample.size();
  double err = 0;
  std::vector<float> series(W);
  for (std::uint64_t i = 0; i < S; ++i) {
    vq_series(sample.means[i], books.c8.data() + std::size_t(books.i8[i]) * 8,
              books.cw.data() + std::size_t(books.iw[i]) * W, W, series.data());
    const float* x = sample.series_of(i, W);
    for (std::uint32_t t = 0; t < n; ++t) err += (double(x[t]) - series[t]) * (double(x[t]) - series[t]);
  }
  return err / (double(S) * n);
}

/// D8 on the sample, then D_W on what the decoded D8 leaves (closed loop); warm from `from`.
TrainedPlainCodebooks train_plain(const Window& win, const TrainingSample& sample, const CodecParams& params,
                           const WarmStart* from) {
  const std::uint32_t K = params.codebook_size, W = win.width;
  const std::uint64_t S = sample.size();
  TrainedPlainCodebooks books;
  std::vector<float> d8(S * 8), r(S * W);
  block_means(win, sample.series.data(), sample.means.data(), S, d8.data());
  books.i8.resize(S);
  books.iw.resize(S);
  LbgOptions lbg{K, params.cold_iterations, params.warm_iterations, params.seed};
  books.c8 = train_lbg(d8.data(), S, 8, lbg, from ? &from->c8 : nullptr);
  NearestSearch(books.c8.data(), K, 8).nearest(d8.data(), S, books.i8.data());
  remove_d8(win, books.c8, sample.series.data(), sample.means.data(), books.i8.data(), S, r.data());
  lbg.seed = params.seed + 1;
  books.cw = train_lbg(r.data(), S, W, lbg, from ? &from->cw : nullptr);
  NearestSearch(books.cw.data(), K, W).nearest(r.data(), S, books.iw.data());
  books.mse = plain_sample_mse(win, sample, books);
  return books;
}

/// The sample's aligned frames, and every second of them (still stratified) to train on: that
/// halves the aligned training at little loss of accuracy, and the codebook is still scored on
/// all of them, as the plain codebooks are, so that the two compare fairly.
struct AlignedTrainingSet {
  std::vector<float> u, u_train;
  std::vector<std::uint32_t> offsets, offsets_train;
};

AlignedTrainingSet aligned_training_set(const Window& win, const AlignedFrames& frames, const TrainingSample& sample) {
  constexpr std::uint64_t stride = 2;
  const std::uint64_t S = sample.size();
  const std::uint32_t dim = frames.dim;
  AlignedTrainingSet set;
  frames.frame(sample.series.data(), sample.vertices.data(), 0, S, win.width, win.steps, set.u, set.offsets);
  for (std::uint64_t i = 0; i < S; i += stride) {
    set.u_train.insert(set.u_train.end(), set.u.begin() + i * dim, set.u.begin() + (i + 1) * dim);
    set.offsets_train.push_back(set.offsets[i]);
  }
  return set;
}

/// The aligned codebook from `init` (warm) or from scratch (null), assigned to the whole sample.
TrainedAlignedCodebook train_aligned(const Window& win, const AlignedFrames& frames, const TrainingSample& sample,
                              const CodecParams& params, const std::vector<float>* init) {
  const std::uint32_t K = params.codebook_size, n = win.steps, dim = frames.dim;
  const std::uint64_t S = sample.size();
  const AlignedTrainingSet set = aligned_training_set(win, frames, sample);
  const PartialVectors train_set{set.u_train.data(), set.offsets_train.data(), set.offsets_train.size(), dim, n};
  // Half the splitting iterations of the plain codebooks: aligned vectors converge faster, and
  // this codebook is trained on top of the plain ones.
  TrainedAlignedCodebook books;
  books.entries = quantise_16bit(train_lbg_partial(train_set, K, std::max(2u, params.cold_iterations / 2),
                                                   params.warm_iterations, params.seed + 2, init));
  const PartialVectors all{set.u.data(), set.offsets.data(), S, dim, n};
  const PartialNearest search(books.entries.values.data(), K, dim, n);
  books.sample_index.resize(S);
  std::vector<float> dist(S);
  parallel_for(S, 512, [&](std::size_t b, std::size_t e) {
    search.nearest(all, b, e - b, books.sample_index.data() + b, dist.data() + b);
  });
  double total = 0;
  for (float d : dist) total += d;
  books.mse = total / (double(S) * n);
  return books;
}

/// A warm start only refines the previous window's entries; when the field changed kind (a
/// transient, a front that swept in and left tails behind), they stay where the old data was
/// and Lloyd iterations do not move them far. Then the kind of codebook the previous page used
/// is also trained cold, and the better codebooks kept. One kind only: a second cold training
/// would double the cost of such a window.
void retrain_stale_codebooks(Training& t, const Window& win, const TrainingSample& sample, const CodecParams& params,
                             const WarmStart* warm, bool warm_aligned) {
  if (!warm) return;
  const bool aligned_leads = t.tried_aligned && warm->aligned_page;
  if (aligned_leads && warm_aligned && t.aligned.mse > 2.0 * warm->ca_mse) {
    TrainedAlignedCodebook cold = timed(t.seconds, [&] { return train_aligned(win, t.frames, sample, params, nullptr); });
    if (cold.mse < t.aligned.mse) t.aligned = std::move(cold);
  } else if (!aligned_leads && t.plain.mse > 2.0 * warm->vq_mse) {
    TrainedPlainCodebooks cold = timed(t.seconds, [&] { return train_plain(win, sample, params, nullptr); });
    if (cold.mse < t.plain.mse) t.plain = std::move(cold);
  }
}

/// Leaves this window's codebooks for the next window's warm start.
void keep_for_next_window(const Training& t, WarmStart& warm) {
  warm.c8 = t.plain.c8;
  warm.cw = t.plain.cw;
  warm.vq_mse = t.plain.mse;
  if (t.tried_aligned) warm.ca = t.aligned.entries.values, warm.ca_mse = t.aligned.mse;
  else warm.ca.clear();
  warm.aligned_page = t.use_aligned;
}

}  // namespace

Training train_codebooks(const Window& win, const TrainingSample& sample, const CodecParams& params, WarmStart* warm) {
  const std::uint32_t K = params.codebook_size, W = win.width;
  const bool warm_fits = warm && warm->c8.size() == std::size_t(K) * 8 && warm->cw.size() == std::size_t(K) * W;
  const WarmStart* from = warm_fits ? warm : nullptr;
  Training t;
  t.plain = timed(t.seconds, [&] { return train_plain(win, sample, params, from); });
  // Shifts are stored in one byte: windows up to 256 steps.
  t.tried_aligned = params.aligned && W <= kMaxAlignedWindow && win.steps >= 2 && t.plain.mse > 0;
  const bool warm_aligned = t.tried_aligned && from && from->ca.size() == std::size_t(K) * (2 * W - 1);
  if (t.tried_aligned) {
    t.frames = align_window(win);
    t.aligned = timed(t.seconds, [&] {
      return train_aligned(win, t.frames, sample, params, warm_aligned ? &from->ca : nullptr);
    });
  }
  retrain_stale_codebooks(t, win, sample, params, from, warm_aligned);
  t.use_aligned = t.tried_aligned && t.aligned.mse < t.plain.mse;
  if (warm) keep_for_next_window(t, *warm);
  return t;
}

void Training::sample_series(const Window& win, const TrainingSample& sample, std::uint64_t i, float* out) const {
  const std::uint32_t W = win.width;
  if (use_aligned) {
    const std::uint64_t v = sample.vertices[i];
    aligned_series(frames.level.values[v], aligned.entries.values.data() + std::size_t(aligned.sample_index[i]) * frames.dim,
                   W, frames.shift[v], win.steps, out);
  } else {
    vq_series(sample.means[i], plain.c8.data() + std::size_t(plain.i8[i]) * 8,
              plain.cw.data() + std::size_t(plain.iw[i]) * W, W, out);
  }
}

}  // namespace penumbra::compression::detail
