// SPDX-License-Identifier: BSD-3-Clause
// compression/src/aligned_lbg.h -- LBG over partially observed vectors (private).
//
// Shift-aligned VQ places each vertex-window of n steps inside a longer frame of D = 2W - 1
// positions so that its largest jump lands at position W - 1 (window_encoder.cpp). A vector
// then covers only positions [offset, offset + n) of the frame; distances and centroids use
// the covered positions only, so where a window happens to start or end never biases the
// codebook.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace penumbra::compression::detail {

/// `count` vectors of `dim` floats (row-major; uncovered positions are ignored), vector i
/// covering [offsets[i], offsets[i] + length).
struct PartialVectors {
  const float* values = nullptr;
  const std::uint32_t* offsets = nullptr;
  std::size_t count = 0;
  std::uint32_t dim = 0, length = 0;
};

/// A codebook (k x dim, row-major) prepared for nearest-entry search over covered ranges.
class PartialNearest {
public:
  /// For vectors covering `length` positions each.
  PartialNearest(const float* codebook, std::uint32_t k, std::uint32_t dim, std::uint32_t length);
  /// Nearest entry of vectors [first, first + count) over their covered positions (ties:
  /// lowest entry), and optionally the squared distance; indices[i - first] for vector i.
  void nearest(const PartialVectors& set, std::size_t first, std::size_t count, std::uint8_t* indices,
               float* distances = nullptr) const;

private:
  std::uint32_t m_dim, m_length, m_kp;  // kp: entries padded to a multiple of 8 (padding: +inf)
  std::vector<float> m_codebook;    // k x dim
  std::vector<float> m_transposed;  // dim x kp
  std::vector<float> m_norms;       // (dim - length + 1) x kp: |entry|^2 over each range
};

/// LBG on partial vectors: splitting initialisation from the masked centroid (cold) or
/// refinement of `init` (warm), as train_lbg. Deterministic for a fixed seed.
std::vector<float> train_lbg_partial(const PartialVectors& set, std::uint32_t k, std::uint32_t iterations_per_split,
                                     std::uint32_t warm_iterations, std::uint64_t seed,
                                     const std::vector<float>* init = nullptr);

}  // namespace penumbra::compression::detail
