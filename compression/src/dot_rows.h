// compression/src/dot_rows.h -- dot products of four vectors with every entry of a transposed
// codebook: the inner loop of the nearest-entry searches (private).
#pragma once
#include <cstddef>
#include <cstdint>

namespace penumbra::compression::detail {

/// Vectors whose dot products one call computes, sharing each load of a codebook row.
constexpr std::size_t kDotRows = 4;

using Lanes8 = float __attribute__((vector_size(32), aligned(4)));  // unaligned loads and stores

/// dot_rows for entries [e0, e0 + 8 kVectors).
template <std::size_t kVectors>
inline __attribute__((always_inline)) void dot_tile(const float* const* x, std::uint32_t a, std::uint32_t n,
                                                    const float* transposed, std::uint32_t kp, std::uint32_t e0,
                                                    float* acc, const float* norms) {
  Lanes8 sums[kDotRows][kVectors] = {};
  for (std::uint32_t j = a; j < a + n; ++j) {
    Lanes8 c[kVectors];
    for (std::size_t v = 0; v < kVectors; ++v)
      c[v] = *reinterpret_cast<const Lanes8*>(transposed + std::size_t(j) * kp + e0 + 8 * v);
    for (std::size_t r = 0; r < kDotRows; ++r) {
      const float xr = x[r][j];
      for (std::size_t v = 0; v < kVectors; ++v) sums[r][v] += xr * c[v];
    }
  }
  for (std::size_t r = 0; r < kDotRows; ++r)
    for (std::size_t v = 0; v < kVectors; ++v) {
      Lanes8& out = *reinterpret_cast<Lanes8*>(acc + r * kp + e0 + 8 * v);
      out = norms ? *reinterpret_cast<const Lanes8*>(norms + e0 + 8 * v) - 2.f * sums[r][v] : sums[r][v];
    }
}

/// acc[r * kp + e] = the sum over j in [a, a + n) of x[r][j] * transposed[j * kp + e], for r <
/// kDotRows and every e < kp (a multiple of 8); with `norms`, norms[e] - 2 times that sum (a
/// squared distance less |x|^2). Each sum adds its products in the order of j,
/// without fused multiply-adds, as a plain loop does. A tile of 16 entries keeps its 4 x 16 sums
/// in registers over the whole range; summed in memory, every multiply-add of 8 entries paid a
/// load and a store, and the searches ran at half the speed. Inlined (no lambdas: they would
/// keep the baseline instruction set) into functions compiled for the instruction set wanted
/// (PNB_AVX2_CLONES, target_region.h).
inline __attribute__((always_inline)) void dot_rows(const float* const* x, std::uint32_t a, std::uint32_t n,
                                                    const float* transposed, std::uint32_t kp, float* acc,
                                                    const float* norms = nullptr) {
  std::uint32_t e0 = 0;
  for (; e0 + 16 <= kp; e0 += 16) dot_tile<2>(x, a, n, transposed, kp, e0, acc, norms);
  if (e0 < kp) dot_tile<1>(x, a, n, transposed, kp, e0, acc, norms);
}

}  // namespace penumbra::compression::detail
