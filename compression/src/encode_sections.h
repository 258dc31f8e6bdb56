// SPDX-License-Identifier: BSD-3-Clause
// compression/src/encode_sections.h -- one vertex's section of a page's BitBlocks, encoded
// (layout in vertex_section.h), and the per-vertex records of a VQ page (private).
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "bit_blocks_builder.h"
#include "bit_io.h"
#include "penumbra/compression/encoded_page.h"
#include "penumbra/core/thread_pool.h"

namespace penumbra::compression::detail {

constexpr std::uint64_t kGroup = BitBlocks::kGroupSize;

/// What one vertex's section costs and its 4-bit code.
struct SectionCost {
  std::uint32_t code;
  std::uint64_t bits;
};

/// Quantised residual of one vertex's `steps` values x against its VQ series `base`, within
/// `bound`; raw float32 values where that cannot hold. Writes nothing when writer is null (cost
/// estimate only). z: scratch of `steps` values.
SectionCost encode_residual_section(const float* x, std::uint32_t steps, const float* base, float step, float bound,
                                    BitWriter* writer, std::uint32_t* z);

/// Error-bounded predictive coding of one vertex: k_t = round((x - q.lo) / q.step), stored as
/// k_0 (q.first_width bits) and the zigzag prediction errors of whichever predictor packs smaller
/// (predictive_layout.h); raw float32 values where that cannot hold. Writes nothing when writer
/// is null. k, z: scratch of `steps` values.
SectionCost encode_predictive_section(const float* x, std::uint32_t steps, const Quantiser& q, float bound,
                                      BitWriter* writer, std::int64_t* k, std::uint32_t* z);

/// The per-vertex records of a VQ page: encode_group(first, last, x) chooses the codewords of
/// vertices [first, last) (x: scratch for their windows, left holding them). With a residual,
/// each vertex's window is then coded against base(v, out), its decoded series, in bit blocks.
template <class EncodeGroup, class Base>
void encode_vq_vertices(EncodedPage& page, std::uint64_t N, std::uint32_t W, std::uint32_t n, bool residual,
                        float step, float bound, const EncodeGroup& encode_group, const Base& base) {
  if (!residual) {
    parallel_for(N, kGroup, [&](std::size_t b, std::size_t e) {
      thread_local std::vector<float> x;
      for (std::size_t g = b; g < e; g += kGroup) encode_group(g, std::min<std::uint64_t>(e, g + kGroup), x);
    });
    return;
  }
  page.quantiser.step = step;
  page.blocks = build_bit_blocks(N, [&](std::uint64_t first, std::uint64_t last, const auto& run) {
    thread_local std::vector<float> x, vbase;
    thread_local std::vector<std::uint32_t> scratch;
    encode_group(first, last, x);
    vbase.resize(W);
    scratch.resize(W);
    run([&](std::uint64_t v, BitWriter& writer) {
      base(v, vbase.data());
      return encode_residual_section(x.data() + (v - first) * W, n, vbase.data(), step, bound, &writer, scratch.data())
          .code;
    });
  });
}

}  // namespace penumbra::compression::detail
