// SPDX-License-Identifier: BSD-3-Clause
// compression/include/penumbra/compression/version.h
#pragma once

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::compression {
/// Version of the compressed field-history container format this build writes. Readers take
/// every version up to this one:
///   1  pages vq, vq_residual, predictive
///   2  adds the shift-aligned pages (vq_aligned, vq_aligned_residual); layouts of the
///      version-1 page kinds are unchanged, so a version-1 file reads as before
///   3  adds predictive_lanes pages (the predictive coder in blocks of 16 vertices); the
///      other layouts are unchanged
///   4  predictive_lanes blocks hold a fourth width, for the steps just after step 1 (a run's
///      transient); version-3 lane pages read with it equal to their later steps' width
///   5  predictive_lanes blocks hold a width for step 2, one for the transient steps after it and
///      where those end (per block); version-3 and -4 lane pages read with their transient steps
///      ending at step 6
///   6  each page's payload follows a 16-byte coding prefix and may be one zstd frame
///      (CodecParams::entropy_level); the payloads' layouts are unchanged
///   7  each page's payload starts with its ValueMap (f64 offset, f64 scale); the index holds
///      each page's map and the field's range in double, in the field's units. Pages of older
///      versions read with the identity map
constexpr int kContainerFormatVersion = 7;
}  // namespace penumbra::compression

PNB_PUBLIC_END
