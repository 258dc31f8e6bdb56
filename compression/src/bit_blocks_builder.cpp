// SPDX-License-Identifier: BSD-3-Clause
// compression/src/bit_blocks_builder.cpp
#include "bit_blocks_builder.h"

#include <cstring>
#include <vector>

#include "penumbra/core/thread_pool.h"

namespace penumbra::compression::detail {

BitBlocks build_bit_blocks(
    std::uint64_t vertex_count,
    const std::function<void(std::uint64_t, std::uint64_t, const std::function<void(const VertexBitsEncoder&)>&)>&
        group_encoder) {
  constexpr std::uint64_t G = BitBlocks::kGroupSize;
  const std::uint64_t groups = (vertex_count + G - 1) / G;
  BitBlocks blocks;
  blocks.widths.assign((vertex_count + 1) / 2, 0);
  blocks.section_bits.assign(vertex_count, 0);
  std::vector<std::vector<std::uint8_t>> group_bytes(groups);
  parallel_for(groups, 8, [&](std::size_t gb, std::size_t ge) {
    for (std::size_t g = gb; g < ge; ++g) {
      const std::uint64_t first = g * G, last = std::min(vertex_count, first + G);
      std::vector<std::uint8_t>& bytes = group_bytes[g];
      BitWriter writer(bytes);
      group_encoder(first, last, [&](const VertexBitsEncoder& encode) {
        for (std::uint64_t v = first; v < last; ++v) {
          blocks.section_bits[v] = std::uint32_t(writer.bit_count());
          const std::uint32_t w = encode(v, writer) & 0xF;
          // Two vertices share a width byte, and both lie in this group (G is even).
          blocks.widths[v >> 1] |= std::uint8_t(w << ((v & 1) * 4));
        }
      });
      writer.flush();
    }
  });
  blocks.group_offsets.resize(groups + 1);
  std::uint64_t total = 0;
  for (std::uint64_t g = 0; g < groups; ++g) {
    blocks.group_offsets[g] = total;
    total += group_bytes[g].size();
  }
  blocks.group_offsets[groups] = total;
  blocks.payload.assign(total + 8, 0);
  for (std::uint64_t g = 0; g < groups; ++g)
    if (!group_bytes[g].empty())
      std::memcpy(blocks.payload.data() + blocks.group_offsets[g], group_bytes[g].data(), group_bytes[g].size());
  return blocks;
}

}  // namespace penumbra::compression::detail
