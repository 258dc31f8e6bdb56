// SPDX-License-Identifier: BSD-3-Clause
// compression/src/lbg_split.h -- the splitting step shared by the two LBG trainers (private)
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "splitmix.h"

namespace penumbra::compression::detail {

/// LBG's splitting step. The min(have, k - have) cells with the largest error (worst first, so
/// that the worst split first when k is not a power of two) each become two entries: the cell's
/// own and a twin appended after `have`, moved apart by +- half the cell's spread along each axis
/// (sigma(e, j)) with random signs, so twins separate along the directions in which the cell
/// actually varies. `codebook` is have x dim on entry; returns the new entry count.
template <class Sigma>
std::uint32_t split_worst_cells(std::vector<float>& codebook, std::uint32_t have, std::uint32_t k, std::uint32_t dim,
                                const std::vector<double>& cell_error, const Sigma& sigma, std::uint64_t& rng) {
  std::vector<std::uint32_t> order(have);
  for (std::uint32_t e = 0; e < have; ++e) order[e] = e;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return cell_error[a] > cell_error[b]; });
  const std::uint32_t splits = std::min(have, k - have);
  codebook.resize(std::size_t(have + splits) * dim);
  for (std::uint32_t s = 0; s < splits; ++s) {
    const std::size_t e = order[s], twin = have + s;
    for (std::uint32_t j = 0; j < dim; ++j) {
      const double spread = sigma(e, j);
      const double delta = 0.5 * spread * ((splitmix(rng) & 1) ? 1.0 : -1.0) + 1e-12;
      const float c = codebook[e * dim + j];
      codebook[e * dim + j] = float(c + delta);
      codebook[twin * dim + j] = float(c - delta);
    }
  }
  return have + splits;
}

}  // namespace penumbra::compression::detail
