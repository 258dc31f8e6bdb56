// SPDX-License-Identifier: BSD-3-Clause
// compression/src/aligned_lbg.cpp
#include "aligned_lbg.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "penumbra/core/error.h"
#include "dot_rows.h"
#include "lbg_split.h"
#include "target_region.h"
#include "penumbra/core/thread_pool.h"

namespace penumbra::compression::detail {

namespace {

// For `rows` (<= kDotRows) vectors sharing the range [a, a + n): each one's nearest entry over that
// range (the first lowest |c|^2 - 2 x.c, from norms over the range; none under +inf: 0).
PNB_AVX2_CLONES void nearest_over_range(const float* const* x, std::size_t rows, std::uint32_t a, std::uint32_t n,
                                        const float* transposed, const float* norms, std::uint32_t kp, float* acc,
                                        std::uint32_t* best) {
  const float* row_x[kDotRows];
  for (std::size_t r = 0; r < kDotRows; ++r) row_x[r] = x[r < rows ? r : 0];
  dot_rows(row_x, a, n, transposed, kp, acc, norms);
  for (std::size_t r = 0; r < rows; ++r)
    best[r] = first_lowest(acc + r * kp, kp, std::numeric_limits<float>::infinity());
}

double assign_all(const PartialVectors& set, const std::vector<float>& codebook, std::uint32_t k,
                  std::vector<std::uint8_t>& idx, std::vector<float>& dist) {
  const PartialNearest search(codebook.data(), k, set.dim, set.length);
  parallel_for(set.count, 512, [&](std::size_t b, std::size_t e) {
    search.nearest(set, b, e - b, idx.data() + b, dist.data() + b);
  });
  double total = 0;
  for (std::size_t i = 0; i < set.count; ++i) total += dist[i];
  return total / double(std::max<std::size_t>(set.count, 1));
}

// Each entry moves to the mean of its members at every position they cover (positions no
// member covers keep their value). Empty cells take the worst-represented vector.
void update_centroids(const PartialVectors& set, std::uint32_t k, std::vector<float>& codebook,
                      const std::vector<std::uint8_t>& idx, std::vector<float>& dist) {
  const std::uint32_t D = set.dim;
  std::vector<double> sum(std::size_t(k) * D, 0.0);
  std::vector<std::uint32_t> members(std::size_t(k) * D, 0), cells(k, 0);
  for (std::size_t i = 0; i < set.count; ++i) {
    const std::size_t e = idx[i];
    ++cells[e];
    const float* x = set.values + i * D;
    for (std::uint32_t j = set.offsets[i]; j < set.offsets[i] + set.length; ++j) {
      sum[e * D + j] += x[j];
      ++members[e * D + j];
    }
  }
  for (std::size_t c = 0; c < std::size_t(k) * D; ++c)
    if (members[c]) codebook[c] = float(sum[c] / members[c]);
  for (std::uint32_t e = 0; e < k; ++e) {
    if (cells[e] != 0 || set.count == 0) continue;
    const std::size_t worst = std::size_t(std::max_element(dist.begin(), dist.begin() + set.count) - dist.begin());
    const float* x = set.values + worst * D;
    for (std::uint32_t j = set.offsets[worst]; j < set.offsets[worst] + set.length; ++j)
      codebook[std::size_t(e) * D + j] = x[j];
    dist[worst] = 0.f;
  }
}

double lloyd(const PartialVectors& set, std::uint32_t k, std::vector<float>& codebook, std::uint32_t iterations) {
  std::vector<std::uint8_t> idx(set.count);
  std::vector<float> dist(set.count);
  double previous = std::numeric_limits<double>::infinity(), mse = previous;
  for (std::uint32_t it = 0; it < iterations; ++it) {
    mse = assign_all(set, codebook, k, idx, dist);
    if (std::isfinite(previous) && previous - mse <= 1e-5 * previous) break;
    previous = mse;
    update_centroids(set, k, codebook, idx, dist);
  }
  return mse;
}

}  // namespace

PartialNearest::PartialNearest(const float* codebook, std::uint32_t k, std::uint32_t dim, std::uint32_t length)
    : m_dim(dim), m_length(length), m_kp((k + 7) / 8 * 8) {
  require(k >= 1 && k <= 256 && length >= 1 && length <= dim, "PartialNearest: bad codebook or length");
  m_codebook.assign(codebook, codebook + std::size_t(k) * dim);
  m_transposed.assign(std::size_t(dim) * m_kp, 0.f);
  std::vector<double> prefix(std::size_t(dim + 1) * m_kp, 0.0);
  for (std::uint32_t e = 0; e < k; ++e)
    for (std::uint32_t j = 0; j < dim; ++j) {
      const float c = codebook[std::size_t(e) * dim + j];
      m_transposed[std::size_t(j) * m_kp + e] = c;
      prefix[std::size_t(j + 1) * m_kp + e] = prefix[std::size_t(j) * m_kp + e] + double(c) * c;
    }
  // Squared norm of every entry over every range [a, a + length); padding entries: infinite.
  const std::uint32_t offsets = dim - length + 1;
  m_norms.assign(std::size_t(offsets) * m_kp, std::numeric_limits<float>::infinity());
  for (std::uint32_t a = 0; a < offsets; ++a)
    for (std::uint32_t e = 0; e < k; ++e)
      m_norms[std::size_t(a) * m_kp + e] =
          float(prefix[std::size_t(a + length) * m_kp + e] - prefix[std::size_t(a) * m_kp + e]);
}

void PartialNearest::nearest(const PartialVectors& set, std::size_t first, std::size_t count, std::uint8_t* indices,
                             float* distances) const {
  require(set.length == m_length && set.dim == m_dim, "PartialNearest: vectors do not match the search");
  // Vectors with the same range are scored four at a time; visiting them in range order
  // (stable, so ties keep vector order) makes such runs long.
  std::vector<std::uint32_t> order(count);
  for (std::size_t i = 0; i < count; ++i) order[i] = std::uint32_t(i);
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) {
    return set.offsets[first + p] < set.offsets[first + q];
  });
  std::vector<float> acc(kDotRows * std::size_t(m_kp));
  for (std::size_t at = 0; at < count;) {
    const std::uint32_t a = set.offsets[first + order[at]];
    std::size_t rows = 1;
    while (rows < kDotRows && at + rows < count && set.offsets[first + order[at + rows]] == a) ++rows;
    const float* x[kDotRows];
    for (std::size_t r = 0; r < rows; ++r) x[r] = set.values + (first + order[at + r]) * m_dim;
    std::uint32_t nearest[kDotRows];
    nearest_over_range(x, rows, a, m_length, m_transposed.data(), m_norms.data() + std::size_t(a) * m_kp, m_kp,
                       acc.data(), nearest);
    for (std::size_t r = 0; r < rows; ++r) {
      const std::uint32_t best = nearest[r];
      const std::size_t i = order[at + r];
      indices[i] = std::uint8_t(best);
      if (distances) {
        const float* c = m_codebook.data() + std::size_t(best) * m_dim;
        float d = 0;
        for (std::uint32_t j = a; j < a + m_length; ++j) d += (x[r][j] - c[j]) * (x[r][j] - c[j]);
        distances[i] = d;
      }
    }
    at += rows;
  }
}

std::vector<float> train_lbg_partial(const PartialVectors& set, std::uint32_t k, std::uint32_t iterations_per_split,
                                     std::uint32_t warm_iterations, std::uint64_t seed, const std::vector<float>* init) {
  const std::uint32_t D = set.dim;
  require(k >= 1 && k <= 256 && set.count >= 1 && set.length >= 1 && set.length <= D,
          "train_lbg_partial: bad arguments");
  if (init) {
    require(init->size() == std::size_t(k) * D, "train_lbg_partial: warm-start codebook has the wrong size");
    std::vector<float> codebook = *init;
    lloyd(set, k, codebook, std::max(1u, warm_iterations));
    return codebook;
  }
  // Masked centroid; positions no vector covers take the nearest covered position's value.
  std::vector<double> sum(D, 0.0);
  std::vector<std::size_t> cover(D, 0);
  for (std::size_t i = 0; i < set.count; ++i)
    for (std::uint32_t j = set.offsets[i]; j < set.offsets[i] + set.length; ++j) sum[j] += set.values[i * D + j], ++cover[j];
  std::vector<float> codebook(D, 0.f);
  for (std::uint32_t j = 0; j < D; ++j)
    if (cover[j]) codebook[j] = float(sum[j] / double(cover[j]));
  for (std::uint32_t j = 1; j < D; ++j)
    if (!cover[j]) codebook[j] = codebook[j - 1];
  for (std::uint32_t j = D - 1; j-- > 0;)
    if (!cover[j] && cover[j + 1]) codebook[j] = codebook[j + 1];

  std::uint64_t rng = seed;
  std::uint32_t have = 1;
  std::vector<std::uint8_t> idx(set.count);
  std::vector<float> dist(set.count);
  while (have < k) {
    assign_all(set, codebook, have, idx, dist);
    std::vector<double> cell_error(have, 0.0), spread(std::size_t(have) * D, 0.0);
    std::vector<std::size_t> members(std::size_t(have) * D, 0);
    for (std::size_t i = 0; i < set.count; ++i) {
      const std::size_t e = idx[i];
      cell_error[e] += dist[i];
      for (std::uint32_t j = set.offsets[i]; j < set.offsets[i] + set.length; ++j) {
        const double d = double(set.values[i * D + j]) - codebook[e * D + j];
        spread[e * D + j] += d * d;
        ++members[e * D + j];
      }
    }
    have = split_worst_cells(codebook, have, k, D, cell_error, [&](std::size_t e, std::uint32_t j) {
      const std::size_t c = e * D + j;
      return members[c] ? std::sqrt(spread[c] / double(members[c])) : 0.0;
    }, rng);
    lloyd(set, have, codebook, std::max(1u, iterations_per_split));
  }
  return codebook;
}

}  // namespace penumbra::compression::detail
