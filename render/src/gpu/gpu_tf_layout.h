// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/gpu_tf_layout.h -- the transfer function as linear pieces for the shader
#pragma once
#include <vector>

#include "penumbra/render/transfer_function.h"

namespace penumbra::render::gpu {

/// Floats per piece: s_ref, tau(s_ref), dtau/ds, empty flag, colour(s_ref) rgb, 0, dcolour/ds rgb, 0.
inline constexpr int kTfPieceFloats = 12;

/// The pieces of the CPU caster's table (see tf_table.h: cut at every breakpoint, extinction and
/// colour linear in each piece, clamped ends), each written around its lower breakpoint s_ref so
/// that float32 evaluation does not cancel for data far from zero. Layout: breakpoint_count + 1
/// pieces of kTfPieceFloats, then the breakpoint_count sorted breakpoints.
struct GpuTfLayout {
  std::vector<float> data;
  int breakpoint_count = 0;
};

/// Extinction is written per unit of a frame `length_scale` world units long (LocalFrame::scale),
/// converted in double: float32 then holds it for any world unit the transfer function uses.
GpuTfLayout build_gpu_tf_layout(const TransferFunction& tf, double length_scale = 1.0);

/// The coefficients c[n][j] (n, j <= 7, at n * 8 + j) of the double series of 1 - Z(a, b) in a
/// and k = (b - a)/2 (segment_integral.h), with c[0][0] dropped and signs flipped.
std::vector<float> one_minus_z_series();

}  // namespace penumbra::render::gpu
