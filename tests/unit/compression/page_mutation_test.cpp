// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/page_mutation_test.cpp -- validate_page's contract under random damage:
// a page it accepts decodes without error and reads only its own arrays. The normal build sees
// a crash or an exception; the sanitizer build (scripts/sanitize.sh) also sees every read
// outside an array, which is what an index or offset past what the page holds would cause.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <set>
#include <string>

#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"
#include "test_fields.h"

namespace penumbra::compression {
namespace {

std::vector<std::shared_ptr<const EncodedPage>> pages_of_every_method() {
  // 3003 vertices: lane blocks, a scalar tail and several 512-vertex runs of a residual decode.
  constexpr std::uint64_t N = 3003;
  auto noise = testing::white_noise(N, 37);
  testing::add_outliers(noise);
  auto waves = testing::oscillating_sources(N, 64);
  testing::add_outliers(waves);
  const auto front = testing::relaxing_front(N, 64);
  const CodecParams plain = testing::small_plain_codebooks(), aligned = testing::small_aligned_codebooks();
  using testing::shared_page;
  CodecParams sections;
  sections.predictive_lanes = false;
  return {shared_page(noise, 37, sections, 2e-2f * noise.range()),       // predictive, raw sections
          shared_page(noise, 37, CodecParams{}, 2e-2f * noise.range()),  // predictive_lanes, exceptions
          shared_page(waves, 64, plain, 0),                              // vq
          shared_page(waves, 64, plain, 1e-2f * waves.range()),          // vq_residual
          shared_page(waves, 29, plain, 2e-4f * waves.range()),          // partial window, tight bound
          shared_page(front, 64, aligned, 0),                            // vq_aligned
          shared_page(front, 64, aligned, 1e-2f * front.range())};       // vq_aligned_residual
}

// One random change to what a page's decoders read: an index, a shift, a 4-bit code, a bit of
// the payload, a section's or a group's start, a width, a scale, the codebook size, the payload's
// length or a time.
void damage(EncodedPage& p, std::mt19937_64& rng) {
  auto any = [&](std::size_t size) { return static_cast<std::size_t>(rng() % size); };
  auto scramble = [&](std::vector<std::uint8_t>& v) {
    if (!v.empty()) v[any(v.size())] = static_cast<std::uint8_t>(rng());
  };
  auto flip_a_bit = [&](std::vector<std::uint8_t>& v) {
    if (!v.empty()) v[any(v.size())] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
  };
  BitBlocks& b = p.blocks;
  LaneBlocks& l = p.lanes;
  switch (rng() % 18) {
    case 0: scramble(p.vq.i8); break;
    case 1: scramble(p.vq.iw); break;
    case 2: scramble(p.aligned.ia); break;
    case 3: scramble(p.aligned.shift); break;
    case 4: flip_a_bit(b.widths); break;
    case 5: flip_a_bit(b.payload); break;
    case 6:
      if (!b.section_bits.empty())
        b.section_bits[any(b.section_bits.size())] += static_cast<std::uint32_t>(rng() % 64) - 32;
      break;
    case 7: if (!b.group_offsets.empty()) b.group_offsets[any(b.group_offsets.size())] += (rng() % 16) - 8; break;
    case 8: p.quantiser.first_width = static_cast<std::uint32_t>(rng() % 40); break;
    case 9: if (!p.means.q.empty()) p.means.q[any(p.means.q.size())] = static_cast<std::uint16_t>(rng()); break;
    case 10: p.codebook_size = static_cast<std::uint32_t>(rng() % 300); break;
    case 11: if (b.payload.size() > 16) b.payload.resize(b.payload.size() - 1 - any(8)); break;
    case 12: scramble(l.widths); break;
    case 13:
      if (!l.exception_steps.empty()) l.exception_steps[any(l.exception_steps.size())] = static_cast<std::uint16_t>(rng() % 48);
      break;
    case 14: if (!l.bit_start.empty()) l.bit_start[any(l.bit_start.size())] += (rng() % 64) - 32; break;
    case 15: if (!l.words.empty()) l.words[any(l.words.size())] ^= 1u << (rng() % 32); break;
    case 16: if (!l.exception_lanes.empty()) l.exception_lanes[any(l.exception_lanes.size())] ^= 1u << (rng() % 16); break;
    default: if (!p.times.empty()) p.times[any(p.times.size())] = rng() % 2 ? std::nan("") : -1.0; break;
  }
}

TEST(PageMutation, WhatValidatePageAcceptsDecodesWithinThePage) {
  const auto originals = pages_of_every_method();
  std::set<PageMethod> methods;
  for (const auto& page : originals) methods.insert(page->method);
  ASSERT_EQ(methods.size(), 6u) << "the pages no longer cover every method";
  std::mt19937_64 rng(20261201);
  int accepted = 0, rejected = 0;
  for (int trial = 0; trial < 480; ++trial) {
    const EncodedPage& original = *originals[static_cast<std::size_t>(trial) % originals.size()];
    auto page = std::make_shared<EncodedPage>(original);
    for (int k = 1 + static_cast<int>(rng() % 3); k > 0; --k) damage(*page, rng);
    try {
      validate_page(*page);
    } catch (const Error&) {
      ++rejected;
      continue;
    }  // anything else (a bad_alloc, a length_error) fails the test
    ++accepted;
    const std::string what = std::string("trial ") + std::to_string(trial) + ", " + to_string(page->method);
    const std::uint64_t N = page->vertex_count;
    const std::uint32_t n = page->step_count;
    std::vector<float> window(N * n), step(N), series(n);
    EXPECT_NO_THROW(decode_window(*page, window.data())) << what;
    for (std::uint32_t t = 0; t < n; ++t) EXPECT_NO_THROW(decode_step(*page, t, step.data())) << what;
    StepCursor cursor;
    for (std::uint32_t t : {0u, 1u, 2u, n / 2, n - 1}) EXPECT_NO_THROW(cursor.decode(page, t, step.data())) << what;
    for (std::uint64_t v = 0; v < N; v += 97) EXPECT_NO_THROW(decode_vertex(*page, v, series.data())) << what;
  }
  // Both outcomes are reached often: the damage is neither always caught nor always harmless.
  EXPECT_GT(accepted, 50);
  EXPECT_GT(rejected, 50);
  std::printf("%d damaged pages accepted, %d rejected\n", accepted, rejected);
}

}  // namespace
}  // namespace penumbra::compression
