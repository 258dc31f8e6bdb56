// SPDX-License-Identifier: BSD-3-Clause
// compression/src/encode_predictive.cpp -- predictive pages: every value as an integer
// k = round((x - lo) / step) coded by its prediction error, in per-vertex sections (predictive)
// or in blocks of 16 vertices (predictive_lanes).
#include <string>

#include "encode_sections.h"
#include "encode_stages.h"
#include "lane_blocks.h"
#include "penumbra/core/error.h"

namespace penumbra::compression::detail {

void encode_predictive_page(EncodedPage& page, const Window& win, const MethodChoice& c) {
  page.quantiser = c.quantiser;
  const std::uint32_t W = win.width, n = win.steps;
  page.blocks = build_bit_blocks(win.n_vertices, [&](std::uint64_t first, std::uint64_t last, const auto& run) {
    thread_local std::vector<float> x;
    thread_local std::vector<std::int64_t> k;
    thread_local std::vector<std::uint32_t> z;
    x.resize((last - first) * W);
    k.resize(W);
    z.resize(W);
    win.gather(first, last - first, x.data());
    run([&](std::uint64_t v, BitWriter& writer) {
      return encode_predictive_section(x.data() + (v - first) * W, n, c.quantiser, c.bound, &writer, k.data(), z.data())
          .code;
    });
  });
}

void encode_predictive_lanes_page(EncodedPage& page, const Window& win, const MethodChoice& c) {
  page.quantiser = c.quantiser;
  const Quantiser& q = c.quantiser;
  page.lanes = build_lane_blocks(win.n_vertices, win.steps, win.width, q.lo, q.step, c.bound, q.first_width,
                                 [&](std::uint64_t first, std::uint64_t count, float* x) { win.gather(first, count, x); });
  // The builder leaves the derived tables empty; deriving them checks the blocks as a parser would.
  const std::string error = lane_blocks_error(page, &page.lanes);
  if (!error.empty()) throw Error(ErrorCode::internal_error, "encode_window: lane blocks: " + error);
}

}  // namespace penumbra::compression::detail
