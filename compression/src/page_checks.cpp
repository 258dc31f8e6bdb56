// SPDX-License-Identifier: BSD-3-Clause
// compression/src/page_checks.cpp -- a page's contents checked value by value.
#include "page_checks.h"

#include <algorithm>
#include <cmath>

#include "huge_pages.h"
#include "lane_blocks.h"
#include "page_methods.h"
#include "vertex_section.h"

namespace penumbra::compression::detail {
namespace {

// Exception positions of a patched section strictly increase and lie inside the window: the
// one-step decoder stops its scan at the first position past the step it wants.
bool exceptions_increasing(const std::uint8_t* data, const VertexSection& s, const EncodedPage& p) {
  const std::uint32_t count = p.method == PageMethod::predictive ? p.step_count - 1 : p.step_count;
  const std::uint32_t pb = position_bits(count);
  std::uint64_t at = s.values.exception_list;
  std::int64_t previous = -1;
  for (std::uint32_t e = 0; e < s.values.exceptions; ++e, at += pb + s.values.exception_width) {
    const std::int64_t position = read_bits(data, at, pb);
    if (position <= previous || position >= std::int64_t(count)) return false;
    previous = position;
  }
  return true;
}

std::string at_vertex(const char* what, std::uint64_t v) { return std::string(what) + " at vertex " + std::to_string(v); }

std::string sections_error(const EncodedPage& p, std::vector<std::uint32_t>* derive) {
  const BitBlocks& b = p.blocks;
  const std::uint64_t N = p.vertex_count, groups = (N + BitBlocks::kGroupSize - 1) / BitBlocks::kGroupSize;
  if (p.method == PageMethod::predictive && (p.quantiser.first_width < 1 || p.quantiser.first_width > 31))
    return "first-value width " + std::to_string(p.quantiser.first_width) + " outside 1..31";
  if (!std::isfinite(p.quantiser.step) || !std::isfinite(p.quantiser.lo)) return "non-finite quantisation step";
  // The tables' sizes and the payload's padding past group_offsets.back() are the page's shape,
  // already checked (see page_contents_error).
  if (b.group_offsets[0] != 0) return "bit payload does not start at 0";
  for (std::uint64_t g = 0; g < groups; ++g)
    if (b.group_offsets[g] > b.group_offsets[g + 1])
      return "group table is not increasing at vertex group " + std::to_string(g);
  if (derive) {
    reserve_on_huge_pages(*derive, N);
    derive->resize(N);
  }
  // Every group's sections must fill exactly its bytes, each parsed without reading past its
  // group: the decoders then never read outside the payload. A group holds at most 128 raw
  // sections of 1024 float32 values, 2^22 bits, so the per-vertex offsets fit 32 bits.
  VertexSection s;
  for (std::uint64_t g = 0; g < groups; ++g) {
    const std::uint64_t base = b.group_offsets[g] * 8, limit = b.group_offsets[g + 1] * 8;
    std::uint64_t pos = base;
    for (std::uint64_t v = g * BitBlocks::kGroupSize; v < std::min(N, (g + 1) * BitBlocks::kGroupSize); ++v) {
      const std::uint32_t offset = std::uint32_t(pos - base);
      if (derive)
        (*derive)[v] = offset;
      else if (b.section_bits[v] != offset)
        return at_vertex("section_bits does not match where the section starts", v);
      if (!parse_vertex(p, b.payload.data(), pos, b.width(v), limit, s))
        return "bits of vertex " + std::to_string(v) + " run past their group";
      // A patched section always has an exception (the encoder patches only to store one); one
      // without any would decode as width-0 plain in lanes but be skipped by the scalar path,
      // which differ in the sign of a zero.
      if (s.code == kPatchedCode && s.values.exceptions == 0)
        return "patched section of vertex " + std::to_string(v) + " has no exceptions";
      if (s.code == kPatchedCode && !exceptions_increasing(b.payload.data(), s, p))
        return "exception list of vertex " + std::to_string(v) + " is out of order";
      pos = s.end;
    }
    if ((pos + 7) / 8 != b.group_offsets[g + 1])
      return "bit block of vertex group " + std::to_string(g) + " has the wrong size";
  }
  return {};
}

}  // namespace

std::string page_contents_error(const EncodedPage& p, std::vector<std::uint32_t>* derive) {
  const std::uint64_t N = p.vertex_count, K = p.codebook_size;
  if (uses_plain_vq(p.method))
    for (std::uint64_t v = 0; v < N; ++v)
      if (p.vq.i8[v] >= K || p.vq.iw[v] >= K) return at_vertex("codebook index out of range", v);
  if (uses_aligned_vq(p.method))
    for (std::uint64_t v = 0; v < N; ++v)
      if (p.aligned.ia[v] >= K || p.aligned.shift[v] >= p.step_count) return at_vertex("aligned codebook index or shift out of range", v);
  if (has_bit_blocks(p.method)) return sections_error(p, derive);
  if (p.method == PageMethod::predictive_lanes) return lane_blocks_error(p, nullptr);
  return {};
}

}  // namespace penumbra::compression::detail
