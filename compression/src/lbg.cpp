// SPDX-License-Identifier: BSD-3-Clause
// compression/src/lbg.cpp -- nearest-entry search and LBG codebook training.
#include "penumbra/compression/lbg.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "dot_rows.h"
#include "lbg_split.h"
#include "target_region.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"

namespace penumbra::compression {

namespace {

constexpr std::size_t kRows = detail::kDotRows;  // vectors scored together

// Scores kRows vectors against all entries: |c|^2 - 2 x.c (|x|^2 is common to all entries).
// Rows past `rows` repeat the first vector; their scores are not read. Compiled for AVX2 and
// baseline; the loader picks one at run time. Results are identical for a fixed machine, which
// is all the encoder's determinism needs.
PNB_AVX2_CLONES void score_rows(const float* x, std::size_t rows, std::uint32_t dim, const float* transposed,
                                const float* norms, std::uint32_t kp, float* acc) {
  const float* row_x[kRows];
  for (std::size_t r = 0; r < kRows; ++r) row_x[r] = x + (r < rows ? r : 0) * dim;
  detail::dot_rows(row_x, 0, dim, transposed, kp, acc, norms);
}

// The entry a scan from best = 0 picks: the first lowest score, a NaN never replacing a number
// (padding entries score +inf, so never win).
PNB_AVX2_CLONES std::uint32_t lowest_score(const float* s, std::uint32_t kp) {
  return std::isnan(s[0]) ? 0 : detail::first_lowest(s, kp, s[0]);
}

}  // namespace

NearestSearch::NearestSearch(const float* codebook, std::uint32_t k, std::uint32_t dim)
    : m_k(k), m_dim(dim), m_k_padded((k + 7) / 8 * 8) {
  require(k >= 1 && k <= 256, "NearestSearch: codebook size must be 1..256, got " + std::to_string(k));
  m_transposed.assign(std::size_t(dim) * m_k_padded, 0.f);
  m_norms.assign(m_k_padded, std::numeric_limits<float>::infinity());
  for (std::uint32_t e = 0; e < k; ++e) {
    double norm = 0;
    for (std::uint32_t j = 0; j < dim; ++j) {
      const float c = codebook[std::size_t(e) * dim + j];
      m_transposed[std::size_t(j) * m_k_padded + e] = c;
      norm += double(c) * c;
    }
    m_norms[e] = float(norm);
  }
}

void NearestSearch::nearest(const float* vectors, std::size_t count, std::uint8_t* indices, float* distances) const {
  std::vector<float> acc(kRows * m_k_padded);
  for (std::size_t i = 0; i < count; i += kRows) {
    const std::size_t rows = std::min(kRows, count - i);
    score_rows(vectors + i * m_dim, rows, m_dim, m_transposed.data(), m_norms.data(), m_k_padded, acc.data());
    for (std::size_t r = 0; r < rows; ++r) {
      const std::uint32_t best = lowest_score(acc.data() + r * m_k_padded, m_k_padded);
      indices[i + r] = std::uint8_t(best);
      if (distances) {
        // Exact distance for the chosen entry (the scored form loses |x|^2 and precision).
        const float* x = vectors + (i + r) * m_dim;
        float d = 0;
        for (std::uint32_t j = 0; j < m_dim; ++j) {
          const float diff = x[j] - m_transposed[std::size_t(j) * m_k_padded + best];
          d += diff * diff;
        }
        distances[i + r] = d;
      }
    }
  }
}

void NearestSearch::nearest_m(const float* vectors, std::size_t count, std::uint32_t m, std::uint8_t* indices) const {
  m = std::min(m, m_k);
  std::vector<float> acc(kRows * m_k_padded);
  std::vector<std::pair<float, std::uint32_t>> best(m);
  for (std::size_t i = 0; i < count; i += kRows) {
    const std::size_t rows = std::min(kRows, count - i);
    score_rows(vectors + i * m_dim, rows, m_dim, m_transposed.data(), m_norms.data(), m_k_padded, acc.data());
    for (std::size_t r = 0; r < rows; ++r) {
      const float* s = acc.data() + r * m_k_padded;
      // Insertion into a sorted list of m: m is small (a handful of candidates).
      std::uint32_t have = 0;
      for (std::uint32_t e = 0; e < m_k; ++e) {
        if (have == m && !(s[e] < best[m - 1].first)) continue;
        std::uint32_t at = have < m ? have++ : m - 1;
        while (at > 0 && s[e] < best[at - 1].first) {
          best[at] = best[at - 1];
          --at;
        }
        best[at] = {s[e], e};
      }
      for (std::uint32_t j = 0; j < m; ++j) indices[(i + r) * m + j] = std::uint8_t(best[j].second);
    }
  }
}

namespace {

// Parallel nearest-entry assignment of all training vectors.
double assign_all(const float* vectors, std::size_t count, std::uint32_t dim, const std::vector<float>& codebook,
                  std::uint32_t k, std::vector<std::uint8_t>& idx, std::vector<float>& dist) {
  const NearestSearch search(codebook.data(), k, dim);
  parallel_for(count, 512, [&](std::size_t b, std::size_t e) {
    search.nearest(vectors + b * dim, e - b, idx.data() + b, dist.data() + b);
  });
  double total = 0;
  for (std::size_t i = 0; i < count; ++i) total += dist[i];
  return total / double(std::max<std::size_t>(count, 1));
}

// Moves each entry to its cell's centroid (serial, in vector order: deterministic). Empty
// cells take the vector farthest from its entry, which also splits the worst cell.
void update_centroids(const float* vectors, std::size_t count, std::uint32_t dim, std::uint32_t k,
                      std::vector<float>& codebook, const std::vector<std::uint8_t>& idx, std::vector<float>& dist) {
  std::vector<double> sum(std::size_t(k) * dim, 0.0);
  std::vector<std::size_t> members(k, 0);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t e = idx[i];
    ++members[e];
    const float* x = vectors + i * dim;
    double* s = sum.data() + std::size_t(e) * dim;
    for (std::uint32_t j = 0; j < dim; ++j) s[j] += x[j];
  }
  for (std::uint32_t e = 0; e < k; ++e) {
    if (members[e] == 0) continue;
    for (std::uint32_t j = 0; j < dim; ++j)
      codebook[std::size_t(e) * dim + j] = float(sum[std::size_t(e) * dim + j] / double(members[e]));
  }
  for (std::uint32_t e = 0; e < k; ++e) {
    if (members[e] != 0 || count == 0) continue;
    const std::size_t worst = std::size_t(std::max_element(dist.begin(), dist.begin() + count) - dist.begin());
    std::copy(vectors + worst * dim, vectors + (worst + 1) * dim, codebook.begin() + std::size_t(e) * dim);
    dist[worst] = 0.f;  // the next empty cell takes the next-worst vector
  }
}

double lloyd(const float* vectors, std::size_t count, std::uint32_t dim, std::uint32_t k, std::vector<float>& codebook,
             std::uint32_t iterations) {
  std::vector<std::uint8_t> idx(count);
  std::vector<float> dist(count);
  double previous = std::numeric_limits<double>::infinity();
  double mse = previous;
  for (std::uint32_t it = 0; it < iterations; ++it) {
    mse = assign_all(vectors, count, dim, codebook, k, idx, dist);
    // Converged: a further pass would move the entries by (almost) nothing.
    if (std::isfinite(previous) && previous - mse <= 1e-5 * previous) break;
    previous = mse;
    update_centroids(vectors, count, dim, k, codebook, idx, dist);
  }
  return mse;
}

}  // namespace

std::vector<float> train_lbg(const float* vectors, std::size_t count, std::uint32_t dim, const LbgOptions& options,
                             const std::vector<float>* init, double* mse_out) {
  const std::uint32_t k = options.codebook_size;
  require(k >= 1 && k <= 256, "train_lbg: codebook_size must be 1..256, got " + std::to_string(k));
  require(dim >= 1, "train_lbg: dim must be positive");
  require(count >= 1, "train_lbg: no training vectors");
  if (init) {
    require(init->size() == std::size_t(k) * dim, "train_lbg: warm-start codebook has the wrong size");
    std::vector<float> codebook = *init;
    const double mse = lloyd(vectors, count, dim, k, codebook, std::max(1u, options.warm_iterations));
    if (mse_out) *mse_out = mse;
    return codebook;
  }

  // Splitting initialisation: start from the centroid, double until k entries.
  std::vector<double> centroid(dim, 0.0), spread(dim, 0.0);
  for (std::size_t i = 0; i < count; ++i)
    for (std::uint32_t j = 0; j < dim; ++j) centroid[j] += vectors[i * dim + j];
  for (auto& c : centroid) c /= double(count);
  for (std::size_t i = 0; i < count; ++i)
    for (std::uint32_t j = 0; j < dim; ++j) {
      const double d = vectors[i * dim + j] - centroid[j];
      spread[j] += d * d;
    }
  std::vector<float> codebook(dim);
  for (std::uint32_t j = 0; j < dim; ++j) codebook[j] = float(centroid[j]);
  std::uint64_t rng = options.seed;
  std::uint32_t have = 1;
  double mse = 0;
  std::vector<std::uint8_t> idx(count);
  std::vector<float> dist(count);
  while (have < k) {
    assign_all(vectors, count, dim, codebook, have, idx, dist);
    std::vector<double> cell_error(have, 0.0);
    std::vector<std::vector<double>> cell_spread(have, std::vector<double>(dim, 0.0));
    std::vector<std::size_t> cell_count(have, 0);
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint32_t e = idx[i];
      cell_error[e] += dist[i];
      ++cell_count[e];
      for (std::uint32_t j = 0; j < dim; ++j) {
        const double d = double(vectors[i * dim + j]) - codebook[std::size_t(e) * dim + j];
        cell_spread[e][j] += d * d;
      }
    }
    have = detail::split_worst_cells(codebook, have, k, dim, cell_error, [&](std::size_t e, std::uint32_t j) {
      return cell_count[e] ? std::sqrt(cell_spread[e][j] / double(cell_count[e])) : 0.0;
    }, rng);
    mse = lloyd(vectors, count, dim, have, codebook, std::max(1u, options.iterations_per_split));
  }
  if (k == 1) mse = lloyd(vectors, count, dim, 1, codebook, 1);
  if (mse_out) *mse_out = mse;
  return codebook;
}

}  // namespace penumbra::compression
