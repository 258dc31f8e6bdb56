// SPDX-License-Identifier: BSD-3-Clause
// compression/src/cpu_features.h -- the one place that says which vector kernels a build has and
// which of them this CPU runs (private).
//
// The kernels are x86 code (AVX2, AVX-512, PCLMULQDQ intrinsics compiled with target attributes,
// chosen at run time), so they exist only where PNB_X86_KERNELS is 1: every intrinsic include,
// kernel definition and dispatch branch to a kernel sits under `#if PNB_X86_KERNELS`. Everywhere
// else (aarch64, for one) the scalar decoders, which every dispatcher keeps, are all there is, and
// they give the same bits. The dispatchers read cpu_features() once, each into a static of its own
// (section_lanes.cpp, lane_blocks_decoder.cpp, crc32.cpp), so that their hot paths stay one load.
#pragma once

#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define PNB_X86_KERNELS 1
#else
#define PNB_X86_KERNELS 0
#endif

namespace penumbra::compression::detail {

/// What the CPU offers of the instruction sets the kernels use; all false where PNB_X86_KERNELS
/// is 0.
struct CpuFeatures {
  bool avx2 = false;
  bool avx512f = false;
  bool avx512vbmi2 = false;
  bool pclmul = false;  ///< PCLMULQDQ
  bool sse41 = false;   ///< SSE4.1 (the CRC fold extracts its result with it)
};

/// Detected on the first call (thread-safe), the same object after that.
const CpuFeatures& cpu_features() noexcept;

}  // namespace penumbra::compression::detail
