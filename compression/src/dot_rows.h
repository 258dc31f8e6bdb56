// SPDX-License-Identifier: BSD-3-Clause
// compression/src/dot_rows.h -- the inner loops of the nearest-entry searches (private): dot
// products of four vectors with every entry of a transposed codebook, and the lowest score.
#pragma once
#include <cstddef>
#include <cstdint>

namespace penumbra::compression::detail {

/// Vectors whose dot products one call computes, sharing each load of a codebook row.
constexpr std::size_t kDotRows = 4;

using Lanes8 = float __attribute__((vector_size(32)));
using Indices8 = std::int32_t __attribute__((vector_size(32)));

/// 8 floats from or to any address. Through memcpy, which both compilers turn into one unaligned
/// move: clang 14 ignores a reduced alignment on a vector type and emits aligned moves through
/// such pointers, which fault on the codebooks' 4-byte-aligned rows.
/// (By reference: a 32-byte vector passed or returned by value changes the ABI with AVX.)
inline __attribute__((always_inline)) void load8(Lanes8& v, const float* p) { __builtin_memcpy(&v, p, sizeof v); }
inline __attribute__((always_inline)) void store8(float* p, const Lanes8& v) { __builtin_memcpy(p, &v, sizeof v); }

/// dot_rows for entries [e0, e0 + 8 kVectors).
template <std::size_t kVectors>
inline __attribute__((always_inline)) void dot_tile(const float* const* x, std::uint32_t a, std::uint32_t n,
                                                    const float* transposed, std::uint32_t kp, std::uint32_t e0,
                                                    float* acc, const float* norms) {
  Lanes8 sums[kDotRows][kVectors] = {};
  for (std::uint32_t j = a; j < a + n; ++j) {
    Lanes8 c[kVectors];
    for (std::size_t v = 0; v < kVectors; ++v)
      load8(c[v], transposed + std::size_t(j) * kp + e0 + 8 * v);
    for (std::size_t r = 0; r < kDotRows; ++r) {
      const float xr = x[r][j];
      for (std::size_t v = 0; v < kVectors; ++v) sums[r][v] += xr * c[v];
    }
  }
  for (std::size_t r = 0; r < kDotRows; ++r)
    for (std::size_t v = 0; v < kVectors; ++v) {
      Lanes8 out = sums[r][v];
      if (norms) {
        Lanes8 n;
        load8(n, norms + e0 + 8 * v);
        out = n - 2.f * out;
      }
      store8(acc + r * kp + e0 + 8 * v, out);
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

/// The entry the scan "best = 0, least = start; for each e, if s[e] < least then best = e, least =
/// s[e]" picks over kp scores (a multiple of 8): the lowest score under `start`, the first of
/// equal ones; a NaN score never wins, and 0 when none is under `start`. Each vector lane keeps
/// the first lowest of its entries, then the lanes are compared; the scalar scan, a compare and a
/// branch per entry, cost as much as the dot products. Inlined as dot_rows is.
inline __attribute__((always_inline)) std::uint32_t first_lowest(const float* s, std::uint32_t kp, float start) {
  Lanes8 low = {start, start, start, start, start, start, start, start};
  Indices8 at = {}, entry = {0, 1, 2, 3, 4, 5, 6, 7};
  for (std::uint32_t e = 0; e < kp; e += 8, entry += 8) {
    Lanes8 v;
    load8(v, s + e);
    const auto lower = v < low;
    low = lower ? v : low;
    at = lower ? entry : at;
  }
  float least = low[0];
  std::int32_t best = at[0];
  for (int l = 1; l < 8; ++l)
    if (low[l] < least || (low[l] == least && at[l] < best)) least = low[l], best = at[l];
  return std::uint32_t(best);
}

}  // namespace penumbra::compression::detail
