// SPDX-License-Identifier: BSD-3-Clause
// compression/include/penumbra/compression/lbg.h
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::compression {

/// A codebook laid out for nearest-entry search: entries transposed (dim x k) so that the
/// distances to all entries are one vectorisable sweep, plus the squared norm of each entry.
class NearestSearch {
public:
  NearestSearch(const float* codebook, std::uint32_t k, std::uint32_t dim);
  /// indices[i] = argmin_e |vectors[i] - codebook[e]|^2 (ties: lowest e). Optionally the
  /// squared distance. Serial; callers parallelise over vectors.
  void nearest(const float* vectors, std::size_t count, std::uint8_t* indices, float* distances = nullptr) const;
  /// The `m` nearest entries of each vector, nearest first: indices[i * m + j].
  void nearest_m(const float* vectors, std::size_t count, std::uint32_t m, std::uint8_t* indices) const;
  std::uint32_t size() const { return m_k; }
  std::uint32_t dim() const { return m_dim; }

private:
  std::uint32_t m_k, m_dim;
  std::vector<float> m_transposed;  // dim x k_padded
  std::vector<float> m_norms;       // k_padded (padding: +inf)
  std::uint32_t m_k_padded;
};

struct LbgOptions {
  std::uint32_t codebook_size = 256;       ///< 1..256
  std::uint32_t iterations_per_split = 8;  ///< Lloyd iterations after each split (cold)
  std::uint32_t warm_iterations = 6;       ///< Lloyd iterations from a given codebook
  std::uint64_t seed = 1;                  ///< split perturbation signs
};

/// Linde-Buzo-Gray training of a codebook (codebook_size x dim) on `count` vectors. Cold
/// start: from the centroid, every entry is split along its cluster's spread and refined
/// (splitting initialisation). Warm start: refines `init` (same size). Empty cells are
/// re-seeded with the worst-represented vector. Deterministic for a fixed seed.
/// Returns the mean squared error per vector on the training set in *mse if given.
std::vector<float> train_lbg(const float* vectors, std::size_t count, std::uint32_t dim, const LbgOptions& options,
                             const std::vector<float>* init = nullptr, double* mse = nullptr);

}  // namespace penumbra::compression

PNB_PUBLIC_END
