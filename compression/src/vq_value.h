// SPDX-License-Identifier: BSD-3-Clause
// compression/src/vq_value.h -- the one definition of how a VQ value is rebuilt (private).
// Encoder and decoders both call these, so the residual the encoder quantises is measured
// against exactly the floats the decoder produces (the bound then holds bit for bit).
#pragma once
#include <cstdint>

namespace penumbra::compression::detail {

inline float dequantise_mean(float lo, float scale, std::uint16_t q) { return lo + float(q) * scale; }

inline float vq_value(float mean, float c8, float cw) { return (mean + c8) + cw; }

/// Shift-aligned VQ: the vertex's level plus its entry's value at frame position
/// t + window - 1 - shift.
inline float aligned_value(float level, float c) { return level + c; }
inline std::uint32_t aligned_frame_start(std::uint32_t window, std::uint32_t shift) { return window - 1 - shift; }
inline void aligned_series(float level, const float* entry, std::uint32_t window, std::uint32_t shift,
                           std::uint32_t steps, float* out) {
  const float* c = entry + aligned_frame_start(window, shift);
  for (std::uint32_t t = 0; t < steps; ++t) out[t] = aligned_value(level, c[t]);
}

/// The W values of one vertex-window: c8 is the vertex's D8 entry, cw its D_W entry.
inline void vq_series(float mean, const float* c8, const float* cw, std::uint32_t window, float* out) {
  const std::uint32_t block = window / 8;
  for (std::uint32_t t = 0; t < window; ++t) out[t] = vq_value(mean, c8[t / block], cw[t]);
}

}  // namespace penumbra::compression::detail
