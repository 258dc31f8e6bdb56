// SPDX-License-Identifier: BSD-3-Clause
// compression/src/section_lanes.h -- decodes the bit-packed sections of 8 neighbouring
// vertices at once, one AVX2 vector lane each, for residual and predictive pages (private).
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

#include "cpu_features.h"
#include "penumbra/compression/encoded_page.h"

namespace penumbra::compression::detail {

constexpr std::uint64_t kLanes = 8;

/// True when the CPU has AVX2 and set_vector_decode has not turned the lanes off (never in a build
/// without x86 kernels).
bool lanes_active();

#if PNB_X86_KERNELS
/// decode_step of a vq_residual / vq_aligned_residual page: adds step t's residual to out[v]
/// (which holds the VQ value) for v in [b, e).
void residual_step_lanes(const EncodedPage& p, std::uint32_t t, std::uint64_t b, std::uint64_t e, float* out,
                         std::vector<std::uint64_t>& special);

/// decode_window of a residual page for vertices [b, e): adds every step's residual to
/// window[t * vertex_count + v], which holds the VQ values.
void residual_window_lanes(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window,
                           std::vector<std::uint64_t>& special);
#endif  // PNB_X86_KERNELS

/// Vertices a chunk of unpack_residual_lanes holds, and the distance between its step rows of
/// unpacked values. Plain-VQ pages write each chunk's VQ values with the residual added
/// (vq_window), in rows of 2 KB. Against the VQ pass writing rows that a residual pass then read
/// back and wrote again, eeg's residual windows (100K vertices x 128 steps, three alternated
/// runs) decode 20-22 % faster; chunks of 64 and 256 vertices were slower (their short rows), 1024 no faster. The
/// stride is padded by one cache line: at 512 floats the 64 step rows' lines fell into two of
/// the L1 cache's sets and evicted one another (3-5 %).
constexpr std::uint64_t kResidualChunk = 512, kResidualStride = 528;

/// The most steps a page may have for unpack_residual_lanes: its thread's buffer then holds at
/// most 270 KB, which stays in L2. Longer pages add their residual in a pass of its own.
constexpr std::uint32_t kResidualChunkSteps = 128;

/// The residual of up to kResidualChunk vertices, every step, as unpack_residual_lanes leaves it
/// in the calling thread's buffers (valid until its next call there).
struct ResidualLanes {
  const std::uint32_t* z;  ///< zigzag value of step t, lane j at z[t * kResidualStride + j]
  const std::int32_t* adds;  ///< all ones in lanes with a residual to add; zero for code 0 and raw
  float step;                ///< value of one quantisation step
};

#if PNB_X86_KERNELS
/// Unpacks the residual of vertices [v0, v0 + lanes) (lanes a multiple of 8, at most
/// kResidualChunk) of a vq_residual / vq_aligned_residual page of at most kResidualChunkSteps
/// steps; raw vertices are appended to `special`, for the caller's scalar path.
ResidualLanes unpack_residual_lanes(const EncodedPage& p, std::uint64_t v0, std::uint64_t lanes,
                                    std::vector<std::uint64_t>& special);

/// decode_window of a predictive page for vertices [b, e) into window[t * vertex_count + v].
void predictive_window_lanes(const EncodedPage& p, std::uint64_t b, std::uint64_t e, float* window,
                             std::vector<std::uint64_t>& special);
#endif  // PNB_X86_KERNELS

}  // namespace penumbra::compression::detail
