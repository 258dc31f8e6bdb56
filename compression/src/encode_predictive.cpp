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

namespace {

void set_integer_scale(EncodedPage& page, const MethodChoice& choice) {
  page.step = choice.step;
  page.lo = choice.lo;
  page.first_width = choice.first_width;
}

}  // namespace

void encode_predictive_page(EncodedPage& page, const Window& win, const MethodChoice& c) {
  set_integer_scale(page, c);
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
      return encode_predictive_section(x.data() + (v - first) * W, n, c.lo, c.step, c.bound, c.first_width, &writer,
                                       k.data(), z.data())
          .code;
    });
  });
}

void encode_predictive_lanes_page(EncodedPage& page, const Window& win, const MethodChoice& c) {
  set_integer_scale(page, c);
  page.lanes = build_lane_blocks(win.n_vertices, win.steps, win.width, c.lo, c.step, c.bound, c.first_width,
                                 [&](std::uint64_t first, std::uint64_t count, float* x) { win.gather(first, count, x); });
  // The builder leaves the derived tables empty; deriving them checks the blocks as a parser would.
  const std::string error = lane_blocks_error(page, &page.lanes);
  if (!error.empty()) throw Error(ErrorCode::internal_error, "encode_window: lane blocks: " + error);
}

}  // namespace penumbra::compression::detail
