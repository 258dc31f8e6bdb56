// SPDX-License-Identifier: BSD-3-Clause
// compression/src/cpu_features.cpp
#include "cpu_features.h"

namespace penumbra::compression::detail {

namespace {

CpuFeatures detect() noexcept {
  CpuFeatures f;
#if PNB_X86_KERNELS
  f.avx2 = __builtin_cpu_supports("avx2");
  f.avx512f = __builtin_cpu_supports("avx512f");
  f.avx512vbmi2 = __builtin_cpu_supports("avx512vbmi2");
  f.pclmul = __builtin_cpu_supports("pclmul");
  f.sse41 = __builtin_cpu_supports("sse4.1");
#endif
  return f;
}

}  // namespace

const CpuFeatures& cpu_features() noexcept {
  static const CpuFeatures features = detect();
  return features;
}

}  // namespace penumbra::compression::detail
