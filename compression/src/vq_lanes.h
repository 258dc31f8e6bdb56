// SPDX-License-Identifier: BSD-3-Clause
// compression/src/vq_lanes.h -- the VQ part of a decode, the table lookups done 8 vertices at a
// time with AVX2 gathers where the CPU has them (private).
//
// GCC's generic tuning never emits gathers by itself, so these loops stayed scalar even in an
// AVX2 build. Each function computes exactly the float operations of vq_value.h (convert,
// multiply, add; never fused), with or without lanes.
#pragma once
#include <cstdint>

#include "cpu_features.h"

namespace penumbra::compression::detail {

/// out[i] = base[i] + table[index[i] * stride] for i < count (a D_W lookup of a full-window
/// decode: `table` is the codebook at the step's column, `stride` its row length).
void add_entries(const float* table, std::int32_t stride, const std::uint8_t* index, const float* base,
                 std::uint64_t count, float* out);

/// out[k * stride + i] = base[i] + table[row[i] + k] for k < steps (<= 8) and i < count: up to
/// eight steps of a whole-window decode at once (`table` at the first step's column; `row` each
/// vertex's row start). Each vertex's eight values table[row[i]] .. table[row[i] + 7] are one
/// contiguous read (all eight must lie in its row, even when fewer steps are wanted), transposed
/// in registers into the step rows, where a lookup per step gathers them one by one: the gathers
/// bound a decode whose output stays in cache.
void add_rows8(const float* table, const std::int32_t* row, const float* base, std::uint64_t count, float* out,
               std::uint64_t stride, std::uint32_t steps);

/// out[i] = level[i] + table[offset[i]] (an aligned page's full-window decode).
void add_offsets(const float* table, const std::int32_t* offset, const float* level, std::uint64_t count, float* out);

struct ResidualLanes;

/// Whether vq_window applies to pages of this window (given at least 8 vertices): lanes are
/// active and the window is a multiple of 64.
bool vq_window_applies(std::uint32_t window);

/// A whole plain-VQ window, 8 vertices at a time: out[t * stride + i] = vq_value(mean, D8, D_W)
/// for t < steps and i < count. Each vertex's D8 row (8 floats: one per block of steps) and each
/// run of eight steps of its D_W row is one contiguous read, transposed in registers into the
/// step rows; nothing is gathered. Returns false, doing nothing, where it does not apply (no
/// lanes, fewer than 8 vertices, or a window that is not a multiple of 64, whose runs of eight
/// steps would straddle two D8 blocks; always, in a build without x86 kernels).
///
/// With `residual` (vertices 0..count-1 its lanes; count a multiple of 8, at most
/// kResidualChunk), each value is written with its residual already added, as
/// residual_window_lanes would add it: every row is written once instead of written, read back
/// and written again.
#if PNB_X86_KERNELS
bool vq_window(float lo, float scale, const std::uint16_t* mean_q, const float* c8, const std::uint8_t* i8,
               const float* cw, std::uint32_t window, const std::uint8_t* iw, std::uint64_t count, float* out,
               std::uint64_t stride, std::uint32_t steps, const ResidualLanes* residual = nullptr);
#else
inline bool vq_window(float, float, const std::uint16_t*, const float*, const std::uint8_t*, const float*,
                      std::uint32_t, const std::uint8_t*, std::uint64_t, float*, std::uint64_t, std::uint32_t,
                      const ResidualLanes* = nullptr) {
  return false;
}
#endif

/// out[i] = dequantise_mean(lo, scale, mean_q[i]) + t8[i8[i] * 8] (mean + D8 of a block of steps;
/// `t8` is the D8 codebook at the block's column).
void mean_plus_entries(float lo, float scale, const std::uint16_t* mean_q, const float* t8, const std::uint8_t* i8,
                       std::uint64_t count, float* out);

/// out[i] = vq_value(dequantise_mean(lo, scale, mean_q[i]), t8[i8[i] * 8], tw[iw[i] * stride]):
/// one step of a plain-VQ page (`t8`, `tw`: the codebooks at the step's columns, `stride` the
/// D_W codebook's row length). The lookups read the codebooks in place: copying a step's
/// columns out first (2 K strided reads and two allocations per step) had cost more than the
/// decode of a small page itself.
void vq_step_values(float lo, float scale, const std::uint16_t* mean_q, const float* t8, const std::uint8_t* i8,
                    const float* tw, std::int32_t stride, const std::uint8_t* iw, std::uint64_t count, float* out);

/// out[i] = aligned_value(dequantise_mean(lo, scale, mean_q[i]), table[ia[i] * stride - shift[i]]):
/// one step of an aligned page (`table` already points at the step's frame position).
void aligned_step_values(float lo, float scale, const std::uint16_t* mean_q, const float* table,
                         const std::uint8_t* ia, const std::uint8_t* shift, std::int32_t stride, std::uint64_t count,
                         float* out);

}  // namespace penumbra::compression::detail
