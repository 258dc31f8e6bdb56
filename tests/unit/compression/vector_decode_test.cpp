// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/vector_decode_test.cpp -- the vector-lane decoders (8 vertices per AVX2
// lane block) give the same bits as the scalar ones, on every page method with bit blocks and
// every section kind (plain, patched, raw), for window, step and cursor decodes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <set>
#include <string>

#include "cpu_features.h"
#include "lane_blocks.h"
#include "penumbra/compression/window_codec.h"
#include "test_fields.h"

namespace penumbra::compression {
namespace {

using testing::SyntheticField;

// Restores the defaults (vector decoders on, the widest the CPU has) whatever a test does.
struct VectorDecodeGuard {
  ~VectorDecodeGuard() {
    set_vector_decode(true);
    detail::cap_lane_isa(detail::LaneIsa::avx512_vbmi2);
  }
};

// The comparisons need a vector decoder: where there is none (a build without x86 kernels, such
// as aarch64's, or an x86 CPU without AVX2) both sides would be the scalar decoders, so the test
// says it is skipped rather than pass without comparing anything.
#define SKIP_WITHOUT_VECTOR_DECODERS()                                                              \
  if (!vector_decode_active())                                                                      \
  GTEST_SKIP() << "no vector decoders to compare with the scalar ones ("                            \
               << (PNB_X86_KERNELS ? "this CPU has no AVX2" : "this build has no x86 kernels") << ")"

struct Decodes {
  std::vector<float> window, steps, cursor;
};

// The playback order a viewer produces: sequential, then jumps back, repeats and a restart.
std::vector<std::uint32_t> playback_order(std::uint32_t n) {
  std::vector<std::uint32_t> order;
  for (std::uint32_t t = 0; t < n; ++t) order.push_back(t);
  for (std::uint32_t t : {5u, 6u, 7u, n - 1, 0u, 1u, n / 2, n / 2, n / 2 + 1, n / 2 + 2})
    if (t < n) order.push_back(t);  // pages shorter than 8 steps skip the later jumps
  return order;
}

Decodes decode_all(const std::shared_ptr<const EncodedPage>& page, bool vector) {
  set_vector_decode(vector);
  const std::uint64_t N = page->vertex_count;
  const std::uint32_t n = page->step_count;
  Decodes d;
  d.window.resize(N * n);
  decode_window(*page, d.window.data());
  d.steps.resize(N * n);
  for (std::uint32_t t = 0; t < n; ++t) decode_step(*page, t, d.steps.data() + std::uint64_t(t) * N);
  StepCursor cursor;
  std::vector<float> step(N);
  for (std::uint32_t t : playback_order(n)) {
    cursor.decode(page, t, step.data());
    d.cursor.insert(d.cursor.end(), step.begin(), step.end());
  }
  return d;
}

// Window, step and cursor decodes with and without lanes agree bit for bit (memcmp: -0.0f and
// NaN payloads included), and every cursor step equals the window's row.
void expect_lanes_match_scalar(const std::shared_ptr<const EncodedPage>& page, const char* what) {
  const Decodes vec = decode_all(page, true), scalar = decode_all(page, false);
  const std::uint64_t N = page->vertex_count;
  ASSERT_EQ(0, std::memcmp(vec.window.data(), scalar.window.data(), vec.window.size() * 4)) << what;
  ASSERT_EQ(0, std::memcmp(vec.steps.data(), scalar.steps.data(), vec.steps.size() * 4)) << what;
  ASSERT_EQ(0, std::memcmp(vec.window.data(), vec.steps.data(), vec.window.size() * 4)) << what;
  ASSERT_EQ(vec.cursor.size(), scalar.cursor.size());
  ASSERT_EQ(0, std::memcmp(vec.cursor.data(), scalar.cursor.data(), vec.cursor.size() * 4)) << what;
  const auto order = playback_order(page->step_count);
  for (std::size_t i = 0; i < order.size(); ++i)
    ASSERT_EQ(0, std::memcmp(vec.cursor.data() + i * N, vec.window.data() + std::uint64_t(order[i]) * N, N * 4))
        << what << ": cursor read " << i << " (step " << order[i] << ")";
}

TEST(VectorDecode, LanesGiveTheScalarDecodersBitsOnEveryMethodAndSectionKind) {
  SKIP_WITHOUT_VECTOR_DECODERS();
  VectorDecodeGuard guard;
  // 3003 vertices: 375 lane blocks and a tail of 3 for the scalar path.
  constexpr std::uint64_t N = 3003;
  std::set<PageMethod> methods;
  std::set<std::uint32_t> residual_codes, predictive_codes;

  auto noise = testing::white_noise(N, 37);
  testing::add_outliers(noise);
  // Per-vertex sections first; the same fields in lane blocks at the end.
  CodecParams sections, plain = testing::small_plain_codebooks();
  sections.predictive_lanes = plain.predictive_lanes = false;
  CodecParams plain_lanes = plain;
  plain_lanes.predictive_lanes = true;
  auto blobs = testing::smooth_blobs(N, 40);
  testing::add_outliers(blobs);
  auto waves = testing::oscillating_sources(N, 64);
  auto waves_outliers = waves;
  testing::add_outliers(waves_outliers);
  const auto front = testing::relaxing_front(N, 64);
  const CodecParams aligned = testing::small_aligned_codebooks();

  struct Case {
    const char* what;
    const SyntheticField* field;
    std::uint32_t steps;
    CodecParams params;
    float bound;
  };
  const std::vector<Case> cases = {
      {"noise, predictive", &noise, 37, sections, 2e-2f * noise.range()},
      {"noise, partial window", &noise, 21, sections, 5e-3f * noise.range()},
      {"noise, tight bound", &noise, 37, sections, 1e-5f * noise.range()},
      {"blobs, predictive", &blobs, 40, plain, 1e-3f * blobs.range()},
      {"waves, residual", &waves, 64, plain, 1e-2f * waves.range()},
      {"waves, sparse residual", &waves, 64, plain, 5e-2f * waves.range()},
      {"waves with outliers, residual", &waves_outliers, 64, plain, 1e-2f * waves.range()},
      {"waves with outliers, tight bound", &waves_outliers, 64, plain, 2e-4f * waves.range()},
      {"waves with outliers, partial window", &waves_outliers, 29, plain, 1e-2f * waves.range()},
      {"front, aligned residual", &front, 64, aligned, 1e-2f * front.range()},
      {"noise, lane blocks", &noise, 37, CodecParams{}, 2e-2f * noise.range()},
      {"noise, lane blocks, partial window", &noise, 21, CodecParams{}, 5e-3f * noise.range()},
      {"noise, lane blocks, tight bound", &noise, 37, CodecParams{}, 1e-5f * noise.range()},
      {"blobs, lane blocks", &blobs, 40, plain_lanes, 1e-3f * blobs.range()},
  };
  std::uint64_t lane_exceptions = 0;
  for (const Case& c : cases) {
    const auto page = testing::shared_page(*c.field, c.steps, c.params, c.bound);
    methods.insert(page->method);
    if (page->method == PageMethod::predictive_lanes) {
      lane_exceptions += page->lanes.exception_steps.size();
      expect_lanes_match_scalar(page, c.what);
      continue;
    }
    auto& codes = page->method == PageMethod::predictive ? predictive_codes : residual_codes;
    for (std::uint64_t v = 0; v < N; ++v) codes.insert(page->blocks.width(v));
    expect_lanes_match_scalar(page, c.what);
  }
  // The cases reach what they are meant to: every method with bit blocks, and on both kinds
  // of page empty (0), plain, patched (14) and raw (15) sections.
  EXPECT_TRUE(methods.count(PageMethod::predictive));
  EXPECT_TRUE(methods.count(PageMethod::predictive_lanes));
  EXPECT_GT(lane_exceptions, 0u);
  EXPECT_TRUE(methods.count(PageMethod::vq_residual));
  EXPECT_TRUE(methods.count(PageMethod::vq_aligned_residual));
  for (const auto* codes : {&residual_codes, &predictive_codes}) {
    EXPECT_TRUE(codes->count(0) && codes->count(14) && codes->count(15));
    EXPECT_GE(codes->size(), 6u);  // and at least three plain widths
  }
}

// A plain page whose window is a multiple of 64 gets its residual written with the VQ values
// (vq_window); any other window adds it in a pass of its own over the VQ rows. Both paths, with
// every section kind, give the scalar decoders' bits.
TEST(VectorDecode, ResidualPassOfAWindowNotAMultipleOf64GivesTheScalarBits) {
  SKIP_WITHOUT_VECTOR_DECODERS();
  VectorDecodeGuard guard;
  constexpr std::uint64_t N = 3003;
  auto waves = testing::oscillating_sources(N, 96);
  testing::add_outliers(waves);
  CodecParams params = testing::small_plain_codebooks();
  params.window = 96;
  std::set<std::uint32_t> codes;
  for (const float bound : {2e-4f, 1e-2f, 5e-2f}) {  // raw sections, dense, sparse (all-zero blocks)
    const auto page = testing::shared_page(waves, 96, params, bound * waves.range());
    ASSERT_EQ(page->method, PageMethod::vq_residual) << bound;
    for (std::uint64_t v = 0; v < N; ++v) codes.insert(page->blocks.width(v));
    expect_lanes_match_scalar(page, ("window of 96, bound " + std::to_string(bound)).c_str());
  }
  EXPECT_TRUE(codes.count(0) && codes.count(14) && codes.count(15)) << ::testing::PrintToString(codes);
}

TEST(VectorDecode, LanesGiveTheScalarBitsOnVqAndAlignedPages) {
  // The codebook lookups (gathers) of pages without bit blocks.
  SKIP_WITHOUT_VECTOR_DECODERS();
  VectorDecodeGuard guard;
  constexpr std::uint64_t N = 3003;
  const auto waves = testing::oscillating_sources(N, 64);
  const auto front = testing::relaxing_front(N, 64);
  const CodecParams plain = testing::small_plain_codebooks(), aligned = testing::small_aligned_codebooks();
  const auto vq = testing::shared_page(waves, 64, plain, 0.0f);
  const auto shifted = testing::shared_page(front, 64, aligned, 0.0f);
  const auto partial = testing::shared_page(waves, 29, plain, 0.0f);
  ASSERT_EQ(vq->method, PageMethod::vq);
  ASSERT_EQ(shifted->method, PageMethod::vq_aligned);
  // Plain VQ windows are written 16 vertices at a time where the CPU has AVX-512 (3003 vertices:
  // runs of 256, the last with an odd number of eights); capped to AVX2, 8 at a time.
  for (const auto isa : {detail::LaneIsa::avx512, detail::LaneIsa::avx2}) {
    detail::cap_lane_isa(isa);
    const std::string with = " (decoders up to " + std::to_string(int(isa)) + ")";
    expect_lanes_match_scalar(vq, ("plain VQ" + with).c_str());
    expect_lanes_match_scalar(partial, ("plain VQ, partial window" + with).c_str());
  }
  detail::cap_lane_isa(detail::LaneIsa::avx512_vbmi2);
  expect_lanes_match_scalar(shifted, "aligned VQ");
  // Eight steps per row read (add_rows8): a window whose D8 blocks span 16 steps, the shortest
  // window, and aligned partial windows whose last group of steps is short, where the read of
  // eight values ends at a row's last one for a shift of 0.
  CodecParams plain128 = plain;
  plain128.window = 128;
  const auto long_waves = testing::oscillating_sources(N, 128);
  expect_lanes_match_scalar(testing::shared_page(long_waves, 128, plain128, 0.0f), "plain VQ, W = 128");
  expect_lanes_match_scalar(testing::shared_page(long_waves, 101, plain128, 0.0f), "plain VQ, W = 128, 101 steps");
  CodecParams aligned8 = aligned;
  aligned8.window = 8;
  expect_lanes_match_scalar(testing::shared_page(testing::relaxing_front(N, 8), 8, aligned8, 0.0f), "W = 8, 8 steps");
  expect_lanes_match_scalar(testing::shared_page(testing::relaxing_front(N, 5), 5, aligned8, 0.0f), "W = 8, 5 steps");
  const auto partial_front = testing::shared_page(testing::relaxing_front(N, 45), 45, aligned, 0.0f);
  ASSERT_EQ(partial_front->method, PageMethod::vq_aligned);
  expect_lanes_match_scalar(partial_front, "aligned VQ, 45 of 64 steps");
}

TEST(VectorDecode, PlainVqWindowsWriteOnlyTheirRowsWhereverTheyStart) {
  // The AVX-512 window decoder joins neighbouring groups of 16 vertices into stores that each
  // cover one cache line of a row, masking a row's first and last lines. Every start of the output
  // within a line, and vertex counts that end a run of 256 with 8 vertices, with 16, or leave
  // fewer than 16 in all, give the scalar bits and write nothing outside the rows.
  SKIP_WITHOUT_VECTOR_DECODERS();
  VectorDecodeGuard guard;
  const CodecParams plain = testing::small_plain_codebooks();
  for (const std::uint64_t N : {8ull, 13ull, 16ull, 40ull, 264ull, 272ull, 530ull, 777ull}) {
    for (const std::uint32_t steps : {21u, 64u}) {
      const auto page = testing::shared_page(testing::oscillating_sources(N, 64), steps, plain, 0.0f);
      ASSERT_EQ(page->method, PageMethod::vq);
      std::vector<float> scalar(N * steps);
      set_vector_decode(false);
      decode_window(*page, scalar.data());
      set_vector_decode(true);
      constexpr std::uint32_t kGuard = 32;  // floats of canary on each side
      std::vector<float> buffer(N * steps + 2 * kGuard + 16);
      const float canary = -12345.5f;
      for (std::uint32_t offset = 0; offset < 16; ++offset) {
        // Offsets within a 64-byte line, counted from the first line-aligned float.
        float* line0 = reinterpret_cast<float*>((reinterpret_cast<std::uintptr_t>(buffer.data()) + 63) & ~std::uintptr_t(63));
        float* out = line0 + kGuard / 2 + offset;
        ASSERT_LE(out + N * steps + kGuard / 2, buffer.data() + buffer.size());
        std::fill(buffer.begin(), buffer.end(), canary);
        decode_window(*page, out);
        const std::string what = "N " + std::to_string(N) + ", " + std::to_string(steps) + " steps, offset " +
                                 std::to_string(offset);
        ASSERT_EQ(0, std::memcmp(out, scalar.data(), scalar.size() * 4)) << what;
        for (float* f = buffer.data(); f < out; ++f) ASSERT_EQ(*f, canary) << what << ": before the rows";
        for (float* f = out + N * steps; f < buffer.data() + buffer.size(); ++f)
          ASSERT_EQ(*f, canary) << what << ": after the rows";
      }
    }
  }
}

TEST(VectorDecode, CanBeTurnedOffAndOn) {
  VectorDecodeGuard guard;
  set_vector_decode(false);
  EXPECT_FALSE(vector_decode_active());
  set_vector_decode(true);
  EXPECT_EQ(vector_decode_active(), detail::cpu_features().avx2);
}

}  // namespace
}  // namespace penumbra::compression
