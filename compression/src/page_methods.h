// SPDX-License-Identifier: BSD-3-Clause
// compression/src/page_methods.h -- what each PageMethod stores (private).
#pragma once
#include "penumbra/compression/codec_params.h"
#include "penumbra/compression/encoded_page.h"

namespace penumbra::compression::detail {

/// mean + D8 + D_W codebooks (EncodedPage::means, EncodedPage::vq).
inline bool uses_plain_vq(PageMethod m) { return m == PageMethod::vq || m == PageMethod::vq_residual; }
/// level + shift-aligned codebook (EncodedPage::means, EncodedPage::aligned).
inline bool uses_aligned_vq(PageMethod m) {
  return m == PageMethod::vq_aligned || m == PageMethod::vq_aligned_residual;
}
/// Per-vertex bit blocks: a quantised residual on top of VQ, or the predictive coder.
inline bool has_bit_blocks(PageMethod m) {
  return m == PageMethod::vq_residual || m == PageMethod::vq_aligned_residual || m == PageMethod::predictive;
}
/// The predictive coder, in per-vertex sections or in lane blocks.
inline bool is_predictive(PageMethod m) { return m == PageMethod::predictive || m == PageMethod::predictive_lanes; }
constexpr std::uint32_t kMaxMethod = 5;

/// Windows are a multiple of 8 (D8 holds the means of 8 equal sub-blocks) in [8, 1024].
inline bool valid_window(std::uint64_t window) { return window >= 8 && window <= 1024 && window % 8 == 0; }
/// Codebooks hold 2..256 entries (an index is one byte).
inline bool valid_codebook_size(std::uint64_t size) { return size >= 2 && size <= 256; }
/// Shift-aligned pages cover windows up to this many steps (a shift is one byte).
constexpr std::uint32_t kMaxAlignedWindow = 256;

/// Throws Error(invalid_argument), naming `call`, unless the page's shape is one the decoders
/// can read without going out of bounds: a known method, a window that is a multiple of 8 in
/// [8, 1024], 1 <= step_count <= window, codebooks of 2..256 entries, and every array of the
/// size the method needs. O(1), so that it can run for every step: pages from a file were
/// checked value by value when parsed; a page assembled by hand gets that check from
/// validate_page (window_codec.h), and this keeps a wrongly shaped one from being read at all.
void require_decodable(const EncodedPage& p, const char* call);

}  // namespace penumbra::compression::detail
