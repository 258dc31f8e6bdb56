// SPDX-License-Identifier: BSD-3-Clause
// compression/src/vertex_section.h -- one vertex's bits in a page's BitBlocks (private).
//   vq_residual, vq_aligned_residual: values (value_layout.h) of zigzag(q_t), t < n
//   predictive:  1-bit predictor, k_0 (first_width bits), values of the n-1 prediction errors
//   raw (code 15, any method): n float32 values
// Sections follow each other without gaps inside a group; BitBlocks::section_bits (derived
// when a page is built or parsed) holds where each one starts.
#pragma once
#include <cstdint>

#include "penumbra/compression/encoded_page.h"
#include "value_layout.h"

namespace penumbra::compression::detail {

struct VertexSection {
  std::uint32_t code = 0;
  std::uint32_t predictor = 0;
  std::uint64_t first_value = 0;  ///< predictive k_0
  std::uint64_t start = 0;        ///< raw values (code 15)
  ValueSpan values;
  std::uint64_t end = 0;
};

/// Parses the section of a vertex with 4-bit `code` at bit `pos`. Returns false (reading
/// nothing past it) if the section would extend beyond bit `limit`.
inline bool parse_vertex(const EncodedPage& p, const std::uint8_t* data, std::uint64_t pos, std::uint32_t code,
                         std::uint64_t limit, VertexSection& s) {
  const std::uint32_t n = p.step_count;
  s.code = code;
  s.start = pos;
  if (code == BitBlocks::kRawWidth) {
    s.end = pos + 32ull * n;
    return s.end <= limit;
  }
  std::uint32_t count = n;
  if (p.method == PageMethod::predictive) {
    if (pos + 1 + p.quantiser.first_width > limit) return false;
    s.predictor = read_bits(data, pos, 1);
    s.first_value = read_bits(data, pos + 1, p.quantiser.first_width);
    pos += 1 + p.quantiser.first_width;
    count = n - 1;
  }
  if (pos + header_bits(code) > limit) return false;
  s.values = parse_values(data, pos, code, count);
  s.end = s.values.end;
  return s.end <= limit;
}

}  // namespace penumbra::compression::detail
