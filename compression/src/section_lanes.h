// compression/src/section_lanes.h -- decodes the bit-packed sections of 8 neighbouring
// vertices at once, one vector lane each (AVX2 gathers), for residual and predictive pages
// (private).
//
// Every lane reads its own section at its own offset and width, so the page format stays
// per-vertex and randomly accessible; the scalar decoders' cost was the per-vertex chain of
// dependent loads and shifts, not memory. Whole-window decodes and the cursor's seek parse plain
// (codes 0..13) and patched (14) sections in lanes, the exceptions lane by lane; raw sections
// (15) go to the caller's scalar path. One-step decodes take plain sections only and append the
// others to `special`, leaving their outputs (and, for predictive pages, their integers) to the
// caller. Results are bit-identical to the scalar decoders: the same wrapping 32-bit integer
// steps and a float multiply and add that are never fused.
//
// All ranges [b, e) are whole lane blocks: b and e are multiples of 8, except that e may be
// the page's vertex count rounded down to a multiple of 8 (the caller decodes the rest).
#pragma once
#include <cstdint>
#include <vector>

#include "penumbra/compression/encoded_page.h"

namespace penumbra::compression::detail {

constexpr std::uint64_t kLanes = 8;

/// True when the CPU has AVX2 and set_vector_decode has not turned the lanes off.
bool lanes_active();

/// decode_step of a vq_residual / vq_aligned_residual page: adds step t's residual to out[v]
/// (which holds the VQ value) for v in [b, e).
void residual_step_lanes(const EncodedPage& p, std::uint32_t t, std::uint64_t b, std::uint64_t e, float* out,
                         std::vector<std::uint64_t>& special);

/// decode_window of a residual page for vertices [b, e): adds every step's residual to
/// window[t * vertex_count + v], which holds the VQ values.
void residual_window_lanes(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window,
                           std::vector<std::uint64_t>& special);

/// decode_window of a predictive page for vertices [b, e) into window[t * vertex_count + v].
void predictive_window_lanes(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window,
                             std::vector<std::uint64_t>& special);

}  // namespace penumbra::compression::detail
