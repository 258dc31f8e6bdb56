// SPDX-License-Identifier: BSD-3-Clause
// compression/src/target_region.h -- functions compiled for instruction sets beyond the build's
// baseline (private): a region of them, with GCC and with clang,
//
//   PNB_TARGET_REGION_BEGIN("avx512f,avx512vbmi2")
//   ... functions, templates and the lambdas inside them ...
//   PNB_TARGET_REGION_END
//
// A region rather than a target attribute on each function, so that the lambdas inside are
// compiled for it too. GCC's target pragma does that; clang ignores it and has an attribute pragma
// of its own, which reaches lambdas' call operators as well. Callers choose the region's code at
// run time (cpu_features.h). And single functions cloned for AVX2 (PNB_AVX2_CLONES, below).
#pragma once
#include "cpu_features.h"

#define PNB_PRAGMA(text) _Pragma(#text)
#if defined(__clang__)
#define PNB_TARGET_REGION_BEGIN(isa) PNB_PRAGMA(clang attribute push(__attribute__((target(isa))), apply_to = function))
#define PNB_TARGET_REGION_END PNB_PRAGMA(clang attribute pop)
#else
#define PNB_TARGET_REGION_BEGIN(isa) PNB_PRAGMA(GCC push_options) PNB_PRAGMA(GCC target(isa))
#define PNB_TARGET_REGION_END PNB_PRAGMA(GCC pop_options)
#endif

// A function compiled for AVX2 and the baseline, the loader choosing one (an ifunc). Not under
// ThreadSanitizer: the loader runs an ifunc's resolver while it relocates the library, before the
// sanitizer's runtime has started, and the instrumented resolver crashes the process there. That
// build runs the baseline version, as every build without x86 kernels does (no AVX2 to clone for).
#if !PNB_X86_KERNELS
#define PNB_AVX2_CLONES
#elif defined(__SANITIZE_THREAD__)
#define PNB_AVX2_CLONES
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define PNB_AVX2_CLONES
#endif
#endif
#ifndef PNB_AVX2_CLONES
#define PNB_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#endif
