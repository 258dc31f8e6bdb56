// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/pager_streaming_test.cpp -- pager playback and the streaming encoder.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "penumbra/compression/pager.h"
#include "penumbra/compression/streaming_encoder.h"
#include "penumbra/core/error.h"
#include "stream_field.h"
#include "temp_path.h"
#include "test_fields.h"

namespace penumbra::compression {
namespace {

using testing::temp_path;

std::shared_ptr<const CompressedField> make_field(const testing::SyntheticField& f, const std::string& path,
                                                  CodecParams p, StreamingStats* stats = nullptr,
                                                  std::uint64_t budget = 0) {
  const StreamingStats s = testing::stream_field(f, path, p, "f", budget);
  if (stats) *stats = s;
  return CompressedField::open(path);
}

CodecParams params(std::uint32_t window, ErrorBound bound = {}) {
  CodecParams p;
  p.window = window;
  p.codebook_size = 64;
  p.bound = bound;
  return p;
}

TEST(Pager, PagedEqualsUnpagedBitForBitInAnyOrder) {
  const auto f = testing::shock_front(2000, 70);
  const auto field = make_field(f, temp_path("p.pnbf"), params(16, {BoundKind::range_relative, 1e-3}));
  Pager pager(field);
  std::vector<float> a(2000), b(2000);
  std::vector<std::uint64_t> order;
  for (std::uint64_t t = 0; t < 70; ++t) order.push_back(t);
  for (std::uint64_t t : {69, 3, 40, 41, 0, 17, 68, 16}) order.push_back(t);  // random access too
  for (std::uint64_t t : order) {
    pager.read_step(t, a.data());
    field->read_step(t, b.data());
    ASSERT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * 4)) << "step " << t;
  }
  const auto s = pager.stats();
  EXPECT_EQ(s.reads, order.size());
  // Current + next page: their bytes plus the section offsets derived at load (4 per vertex).
  EXPECT_LE(s.peak_resident_bytes, 2 * (field->page(0).bytes + 4 * 2000) + 8192);
}

TEST(Pager, SequentialPlaybackDoesNotStall) {
  const auto f = testing::smooth_blobs(3000, 64);
  const auto field = make_field(f, temp_path("s.pnbf"), params(16));
  Pager pager(field);
  std::vector<float> out(3000);
  // Give the prefetch thread the time a renderer would take per frame (1 ms).
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  for (std::uint64_t t = 0; t < 64; ++t) {
    pager.read_step(t, out.data());
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const auto s = pager.stats();
  EXPECT_EQ(s.stalls, 0u);
  EXPECT_EQ(s.loads, 4u);
  EXPECT_EQ(s.prefetched, 4u);
  // Pages 2 and 3 load into the memory of pages 0 and 1, which playback has left.
  EXPECT_EQ(s.recycled, 2u);
}

TEST(Pager, PlaybackAfterPrepareNeverStallsFromAnyStartingStep) {
  const auto f = testing::smooth_blobs(3000, 64);
  const auto field = make_field(f, temp_path("p.pnbf"), params(16));
  std::vector<float> out(3000), ref(3000);
  for (const std::uint64_t first : {0u, 37u}) {
    Pager pager(field);
    pager.prepare(first);  // no sleep: prepare is what makes the first page resident
    for (std::uint64_t t = first; t < 64; ++t) {
      // A renderer's frame is where the next page's prefetch finishes; on a loaded machine that
      // takes a while, so give it up to 10 s (the reads must still find every page resident).
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
      while (!pager.resident(t) && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      pager.read_step(t, out.data());
      field->read_step(t, ref.data());
      ASSERT_EQ(0, std::memcmp(out.data(), ref.data(), out.size() * 4)) << t;
    }
    const auto s = pager.stats();
    EXPECT_EQ(s.stalls, 0u) << "from step " << first;
    // Each page once (from step 37 the constructor's load of page 0 may or may not have begun).
    if (first == 0) EXPECT_EQ(s.loads, 4u);
    EXPECT_GT(s.prepare_seconds, 0.0);
  }
}

TEST(Pager, StartAtLoadsThatPageInTheBackground) {
  const auto f = testing::smooth_blobs(3000, 64);
  const auto field = make_field(f, temp_path("a.pnbf"), params(16));
  Pager pager(field, {});
  pager.start_at(50);  // page 3; the constructor's load of page 0 is no longer wanted
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!pager.resident(50) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  std::vector<float> out(3000), ref(3000);
  pager.read_step(50, out.data());
  field->read_step(50, ref.data());
  EXPECT_EQ(0, std::memcmp(out.data(), ref.data(), out.size() * 4));
  EXPECT_EQ(pager.stats().stalls, 0u);
  EXPECT_FALSE(pager.resident(0));  // playback moved: page 0 is not kept
  EXPECT_THROW(pager.start_at(64), Error);
  EXPECT_THROW(pager.prepare(64), Error);
}

TEST(Pager, MemoryCapLimitsResidencyAndTooSmallACapIsRejected) {
  const auto f = testing::smooth_blobs(3000, 48);
  // Under a bound the pages' slots compress well on disk.
  const auto field = make_field(f, temp_path("c.pnbf"), params(16, {BoundKind::range_relative, 1e-2}));
  // A page's memory once loaded: its payload with the coding undone, the 64-byte header and,
  // for pages with bit blocks (not plain VQ), 4 bytes per vertex of section offsets.
  ASSERT_NE(field->page(0).method, PageMethod::vq);
  const std::uint64_t page_bytes = field->page(0).payload_bytes + 64 + 4 * 3000;
  EXPECT_THROW(Pager(field, {.memory_cap_bytes = page_bytes / 2}), Error);
  // Compressed on disk, a page takes more than its bytes there: a cap of those is too small.
  ASSERT_LT(field->page(0).bytes, page_bytes);
  EXPECT_THROW(Pager(field, {.memory_cap_bytes = field->page(0).bytes}), Error);
  // Room for one page only: no prefetch, every page switch is a (counted) stall.
  Pager pager(field, {.memory_cap_bytes = page_bytes + page_bytes / 2});
  std::vector<float> out(3000), ref(3000);
  for (std::uint64_t t = 0; t < 48; ++t) {
    pager.read_step(t, out.data());
    field->read_step(t, ref.data());
    ASSERT_EQ(0, std::memcmp(out.data(), ref.data(), out.size() * 4));
  }
  const auto s = pager.stats();
  EXPECT_LE(s.peak_resident_bytes, page_bytes + page_bytes / 2);
  EXPECT_GE(s.stalls, 2u);
}

TEST(StreamingEncoder, MatchesOneShotEncodingAndFlushesThePartialWindow) {
  const auto f = testing::smooth_blobs(2500, 45);
  StreamingStats stats;
  const auto field = make_field(f, temp_path("s.pnbf"), params(16), &stats);
  EXPECT_EQ(stats.pages, 3u);
  EXPECT_EQ(stats.steps, 45u);
  EXPECT_EQ(stats.buffers, 2u);
  EXPECT_EQ(field->page(2).step_count, 13u);
  // The background encoder writes what encode_window gives on the same data, warm-started.
  WarmStart warm;
  std::vector<float> got(2500), want(2500);
  for (std::uint32_t w = 0; w < 3; ++w) {
    const std::uint32_t first = w * 16, n = std::min(16u, 45u - first);
    const auto page = encode_window(f.values.data() + std::uint64_t(first) * 2500, 2500, n, f.times.data() + first,
                                    first, params(16), 0, &warm);
    for (std::uint32_t t = 0; t < n; ++t) {
      decode_step(page, t, want.data());
      field->read_step(first + t, got.data());
      ASSERT_EQ(0, std::memcmp(got.data(), want.data(), got.size() * 4)) << first + t;
    }
  }
}

TEST(StreamingEncoder, BudgetChoosesBuffersOrIsRejected) {
  const auto f = testing::smooth_blobs(1000, 40);
  const auto p = params(16);
  const auto one = StreamingEncoder::required_budget(1000, p, 1);
  StreamingStats stats;
  const auto field = make_field(f, temp_path("b.pnbf"), p, &stats, one);
  EXPECT_EQ(stats.buffers, 1u);
  EXPECT_EQ(field->step_count(), 40u);
  StreamingOptions o;
  o.path = temp_path("tiny.pnbf");
  o.vertex_count = 1000;
  o.codec = p;
  o.memory_budget_bytes = one - 1;
  EXPECT_THROW(StreamingEncoder{o}, Error);
}

TEST(StreamingEncoder, NonFiniteStepIsRejectedAndNotRecorded) {
  const auto f = testing::smooth_blobs(500, 20);
  StreamingOptions o;
  o.path = temp_path("nan.pnbf");
  o.vertex_count = 500;
  o.codec = params(8);
  StreamingEncoder enc(o);
  std::vector<float> bad(f.values.begin(), f.values.begin() + 500);
  bad[7] = std::nanf("");
  for (std::uint32_t t = 0; t < 20; ++t) {
    if (t == 10) {
      EXPECT_THROW(enc.push(99.0, bad.data()), Error);
    }
    enc.push(f.times[t], f.values.data() + t * 500);
  }
  enc.finish();
  const auto field = CompressedField::open(o.path);
  EXPECT_EQ(field->step_count(), 20u);
  EXPECT_EQ(field->times(), f.times);
}

}  // namespace
}  // namespace penumbra::compression
