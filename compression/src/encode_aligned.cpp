// SPDX-License-Identifier: BSD-3-Clause
// compression/src/encode_aligned.cpp -- shift-aligned VQ pages (vq_aligned, vq_aligned_residual):
// per vertex a 16-bit level, a shift and an entry of one codebook over frames of 2W-1 steps.
#include <cmath>

#include "aligned_lbg.h"
#include "encode_sections.h"
#include "encode_stages.h"

namespace penumbra::compression::detail {

namespace {

/// Step of the largest |x[t] - x[t-1]| (the first of equals); the vertex's shift.
std::uint32_t largest_change(const float* x, std::uint32_t n) {
  std::uint32_t best = 0;
  float best_change = -1.f;
  for (std::uint32_t t = 1; t < n; ++t) {
    const float change = std::fabs(x[t] - x[t - 1]);
    if (change > best_change) best_change = change, best = t;
  }
  return best;
}

}  // namespace

AlignedFrames align_window(const Window& win) {
  const std::uint64_t N = win.n_vertices;
  const std::uint32_t W = win.width, n = win.steps;
  AlignedFrames frames;
  frames.dim = 2 * W - 1;
  frames.shift.resize(N);
  std::vector<float> level(N);
  parallel_for(N, kGroup * 8, [&](std::size_t b, std::size_t e) {
    std::vector<float> x((e - b) * W);
    win.gather(b, e - b, x.data());
    for (std::size_t v = b; v < e; ++v) {
      const float* xv = x.data() + (v - b) * W;
      const std::uint32_t s = largest_change(xv, n);
      frames.shift[v] = std::uint8_t(s);
      level[v] = xv[s > 0 ? s - 1 : 0];
    }
  });
  frames.level = quantise_16bit(level);
  return frames;
}

void AlignedFrames::frame(const float* x, const std::uint64_t* vertices, std::uint64_t first, std::uint64_t count,
                          std::uint32_t W, std::uint32_t n, std::vector<float>& u,
                          std::vector<std::uint32_t>& offsets) const {
  u.assign(count * dim, 0.f);
  offsets.resize(count);
  for (std::uint64_t i = 0; i < count; ++i) {
    const std::uint64_t v = vertices ? vertices[i] : first + i;
    const std::uint32_t a = aligned_frame_start(W, shift[v]);
    offsets[i] = a;
    for (std::uint32_t t = 0; t < n; ++t) u[i * dim + a + t] = x[i * W + t] - level.values[v];
  }
}

void encode_aligned_page(EncodedPage& page, const Window& win, const AlignedFrames& frames,
                         const TrainedAlignedCodebook& codebook, const MethodChoice& choice) {
  const std::uint64_t N = win.n_vertices;
  const std::uint32_t W = win.width, n = win.steps, K = page.codebook_size;
  page.means = frames.level.stored();
  AlignedCodebook& aligned = page.aligned;
  aligned.ca = codebook.entries.values;
  aligned.ca_q = codebook.entries.q;
  aligned.ca_lo = codebook.entries.lo;
  aligned.ca_scale = codebook.entries.scale;
  aligned.shift = frames.shift;
  aligned.ia.resize(N);
  const PartialNearest search(aligned.ca.data(), K, frames.dim, n);
  auto encode_group = [&](std::uint64_t first, std::uint64_t last, std::vector<float>& x) {
    thread_local std::vector<float> u;
    thread_local std::vector<std::uint32_t> offsets;
    x.resize((last - first) * W);
    win.gather(first, last - first, x.data());
    frames.frame(x.data(), nullptr, first, last - first, W, n, u, offsets);
    const PartialVectors set{u.data(), offsets.data(), last - first, frames.dim, n};
    search.nearest(set, 0, last - first, aligned.ia.data() + first);
  };
  const bool residual = choice.method == PageMethod::vq_aligned_residual;
  encode_vq_vertices(page, N, W, n, residual, choice.quantiser.step, choice.bound, encode_group,
                     [&](std::uint64_t v, float* out) {
                       aligned_series(frames.level.values[v], aligned.ca.data() + std::size_t(aligned.ia[v]) * frames.dim,
                                      W, aligned.shift[v], n, out);
                     });
}

}  // namespace penumbra::compression::detail
