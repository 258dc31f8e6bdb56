// SPDX-License-Identifier: BSD-3-Clause
// compression/src/step_base.h -- the VQ part of one step of a page (private), shared by
// decode_step and StepCursor, which add a residual on top of it.
#pragma once
#include <cstdint>

#include "penumbra/compression/encoded_page.h"

namespace penumbra::compression::detail {

/// Step t of the VQ part (mean + D8 + D_W, or the aligned level + entry) for vertices [b, e).
void vq_base_step(const EncodedPage& p, std::uint32_t t, std::uint64_t b, std::uint64_t e, float* out);

}  // namespace penumbra::compression::detail
