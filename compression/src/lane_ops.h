// SPDX-License-Identifier: BSD-3-Clause
// compression/src/lane_ops.h -- the AVX2 building blocks the lane decoders share (private):
// 8 lanes loaded, widened or stored. Functions carry the AVX2 target themselves, so callers
// compile without -mavx2 and choose them at run time (section_lanes.h: lanes_active). x86 only
// (cpu_features.h): empty where PNB_X86_KERNELS is 0.
#pragma once
#include "cpu_features.h"

#if PNB_X86_KERNELS
#include <immintrin.h>

#include <cstdint>

#define PNB_LANES __attribute__((target("avx2"), always_inline)) inline

namespace penumbra::compression::detail {

/// 8 bytes or 8 half-words widened to 8 lanes.
PNB_LANES __m256i widen8(const std::uint8_t* at) {
  return _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(at)));
}
PNB_LANES __m256i widen16(const std::uint16_t* at) {
  return _mm256_cvtepu16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(at)));
}

PNB_LANES __m256 load(const float* at) { return _mm256_loadu_ps(at); }
PNB_LANES __m256i load(const std::int32_t* at) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(at)); }
PNB_LANES __m256i load(const std::uint32_t* at) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(at)); }
PNB_LANES void store(float* at, __m256 x) { _mm256_storeu_ps(at, x); }
PNB_LANES void store(std::int32_t* at, __m256i x) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(at), x); }
PNB_LANES void store(std::uint32_t* at, __m256i x) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(at), x); }

/// The signed integers of 8 zigzag codes.
PNB_LANES __m256i unzigzag_lanes(__m256i z) {
  return _mm256_xor_si256(_mm256_srli_epi32(z, 1),
                          _mm256_sub_epi32(_mm256_setzero_si256(), _mm256_and_si256(z, _mm256_set1_epi32(1))));
}

/// base + q * step with the scalar decoders' float operations: convert, multiply, add; never
/// fused (the lane functions' target has no FMA, and the module compiles with -ffp-contract=off).
PNB_LANES __m256 add_scaled(__m256 base, __m256i q, __m256 step) {
  return _mm256_add_ps(base, _mm256_mul_ps(_mm256_cvtepi32_ps(q), step));
}

}  // namespace penumbra::compression::detail

#endif  // PNB_X86_KERNELS
