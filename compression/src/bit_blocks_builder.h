// SPDX-License-Identifier: BSD-3-Clause
// compression/src/bit_blocks_builder.h -- assembles BitBlocks from per-vertex encoders (private).
#pragma once
#include <cstdint>
#include <functional>

#include "bit_io.h"
#include "penumbra/compression/encoded_page.h"

namespace penumbra::compression::detail {

/// Called once per vertex of a group, in vertex order; writes the vertex's bits and returns
/// its 4-bit width code. `scratch` is per-call-of-group memory the callback may use.
using VertexBitsEncoder = std::function<std::uint32_t(std::uint64_t vertex, BitWriter& writer)>;

/// Encodes all vertices, groups in parallel, and concatenates the groups' bytes.
/// `group_encoder(first, last, encode)` lets the caller prepare per-group data (e.g. gather a
/// block of time series) before encode is called for each vertex of [first, last).
BitBlocks build_bit_blocks(
    std::uint64_t vertex_count,
    const std::function<void(std::uint64_t first, std::uint64_t last, const std::function<void(const VertexBitsEncoder&)>&)>&
        group_encoder);

}  // namespace penumbra::compression::detail
