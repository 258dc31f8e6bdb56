// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/lane_blocks_test.cpp -- predictive_lanes pages: the bound at every value
// on hard windows (one or two steps, a partial last block, exceptions, raw lanes), every decode
// path against the window, the table checks, and the file format's version gate.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>

#include "crc32_reference.h"
#include "lane_blocks.h"
#include "page_format.h"
#include "expect_error.h"
#include "penumbra/compression/field_file.h"
#include "penumbra/compression/version.h"
#include "penumbra/compression/window_codec.h"
#include "stream_field.h"
#include "temp_path.h"
#include "test_fields.h"

namespace penumbra::compression {
namespace {

using testing::SyntheticField;
using testing::temp_path;
using testing::crc32_reference;

// Restores the defaults (vector decoders on, the widest the CPU has) whatever a test does.
struct VectorDecodeGuard {
  ~VectorDecodeGuard() {
    set_vector_decode(true);
    detail::cap_lane_isa(detail::LaneIsa::avx512_vbmi2);
  }
};

// Every decoder a test caps the lanes to, widest first; each runs only where the CPU has it
// (has_lane_isa), so that a CPU without it (any, off x86) does not run the same decoder again.
constexpr detail::LaneIsa kEveryLaneIsa[] = {detail::LaneIsa::avx512_vbmi2, detail::LaneIsa::avx512,
                                             detail::LaneIsa::avx2, detail::LaneIsa::scalar};

// Caps the lanes to `isa`; false where the CPU (or the build) has not got it.
bool has_lane_isa(detail::LaneIsa isa) {
  detail::cap_lane_isa(isa);
  return detail::lane_isa() == isa;
}

// Window, every step, every vertex's series and a cursor's playback agree bit for bit with the
// scalar decoders, for each vector decoder this CPU has (AVX-512 with and without VBMI2, AVX2),
// and every value lies within the page's bound.
void expect_paths_agree(const SyntheticField& f, std::uint32_t n, const EncodedPage& page, const std::string& what) {
  VectorDecodeGuard guard;
  const std::uint64_t N = f.vertices;
  ASSERT_EQ(page.method, PageMethod::predictive_lanes) << what;
  std::vector<float> window(N * n), scalar(N * n), step(N), series(n);
  set_vector_decode(false);
  decode_window(page, scalar.data());
  set_vector_decode(true);
  for (std::uint64_t i = 0; i < N * n; ++i)
    ASSERT_LE(std::fabs(double(scalar[i]) - f.values[i]), page.bound) << what << ": value " << i;
  for (const auto isa : kEveryLaneIsa) {
    if (!has_lane_isa(isa)) continue;
    const std::string with = what + ", decoders up to " + std::to_string(int(isa));
    decode_window(page, window.data());
    ASSERT_EQ(0, std::memcmp(window.data(), scalar.data(), window.size() * 4)) << with;
    const auto shared = std::make_shared<const EncodedPage>(page);
    StepCursor cursor;
    for (std::uint32_t t = 0; t < n; ++t) {
      decode_step(page, t, step.data());
      ASSERT_EQ(0, std::memcmp(step.data(), scalar.data() + std::uint64_t(t) * N, N * 4)) << with << ": step " << t;
      cursor.decode(shared, t, step.data());
      ASSERT_EQ(0, std::memcmp(step.data(), scalar.data() + std::uint64_t(t) * N, N * 4)) << with << ": cursor " << t;
    }
  }
  for (std::uint64_t v = 0; v < N; v += 7) {
    decode_vertex(page, v, series.data());
    for (std::uint32_t t = 0; t < n; ++t) ASSERT_EQ(series[t], scalar[std::uint64_t(t) * N + v]) << what << ": vertex " << v;
  }
}

// The page as a file of `version` holds it, parsed back: its words then have no spare capacity
// (the sanitizer build catches a read past them) and its zero row is the parser's.
EncodedPage through_page_bytes(const EncodedPage& page, std::uint32_t version = kContainerFormatVersion) {
  const auto bytes = detail::serialize_page(page, 0, version);
  detail::PageHeader header;
  EXPECT_TRUE(detail::parse_page_header(bytes.data(), header));
  return detail::parse_page_payload(header, bytes.data() + detail::PageHeader::kBytes, page.vertex_count, page.window,
                                    page.codebook_size, "test page", version);
}

TEST(LaneBlocks, EveryPathHoldsTheBoundOnHardWindows) {
  auto noise = testing::white_noise(1003, 40);  // 62 full blocks and a last one of 11 lanes
  testing::add_outliers(noise);
  for (const std::uint32_t n : {1u, 2u, 3u, 21u, 40u}) {
    const float bound = 1e-2f * noise.range();
    const auto page = testing::encode(noise, 0, n, CodecParams{}, bound);
    expect_paths_agree(noise, n, page, "noise, " + std::to_string(n) + " steps");
    // A page of 3 steps holds its outliers in step 2's width (a row is priced above most widths).
    if (n >= 21) EXPECT_GT(page.lanes.exception_steps.size(), 0u) << "outliers should be exceptions";
  }
  // Fewer vertices than one block.
  const auto few = testing::white_noise(5, 9);
  expect_paths_agree(few, 9, testing::encode(few, 0, 9, CodecParams{}, 1e-2f * few.range()), "5 vertices");
}

// Blocks whose lanes all hold their last value (the AVX-512 window then keeps no difference) and
// blocks with extrapolating lanes, both with exception rows, decode alike on every path.
TEST(LaneBlocks, BlocksWithAndWithoutExtrapolatingLanesDecodeAlike) {
  const std::uint64_t N = 64;
  const std::uint32_t n = 40;
  SyntheticField f{N, n, std::vector<float>(N * n), std::vector<double>(n)};
  std::mt19937_64 rng(11);
  std::normal_distribution<float> noise(0.f, 0.02f);
  for (std::uint32_t t = 0; t < n; ++t) {
    f.times[t] = t;
    for (std::uint64_t v = 0; v < N; ++v) {
      const bool ramps = (v / 16) % 2 == 0;
      float x = ramps ? float(v) + 0.5f * float(1 + v % 4) * float(t) : float(v % 7) + noise(rng);
      if (v % 5 == 0 && t == 7 + v % 20) x += 60.f;  // a spike: an exception row
      f.values[std::uint64_t(t) * N + v] = x;
    }
  }
  const auto page = testing::encode(f, 0, n, CodecParams{}, 1e-3f * f.range());
  ASSERT_EQ(page.method, PageMethod::predictive_lanes);
  const LaneBlocks& L = page.lanes;
  int plain_with_rows = 0, linear_with_rows = 0;
  for (std::uint64_t b = 0; b < L.block_count(); ++b) {
    const bool rows = L.row_start[b + 1] > L.row_start[b];
    plain_with_rows += rows && L.linear[b] == 0;
    linear_with_rows += rows && L.linear[b] != 0;
  }
  EXPECT_GT(plain_with_rows, 0);
  EXPECT_GT(linear_with_rows, 0);
  expect_paths_agree(f, n, page, "ramps and noise with spikes");
}

TEST(LaneBlocks, ValuesTheQuantiserCannotHoldAreStoredExactly) {
  // At a bound of 1e-8 of the range, k exceeds 2^24 and lo + float(k) step misses some values
  // by more than the bound: those lanes are stored as exact floats.
  auto f = testing::smooth_blobs(100, 12);
  const float bound = 1e-8f * f.range();
  const auto page = testing::encode(f, 0, 12, CodecParams{}, bound);
  ASSERT_EQ(page.method, PageMethod::predictive_lanes);
  EXPECT_GT(page.lanes.raw_values.size(), 0u);
  expect_paths_agree(f, 12, page, "raw lanes");
}

TEST(LaneBlocks, ZeroWidthStepsAtTheVeryEndOfTheColumnsStayInside) {
  // Two blocks of a constant field with 16-bit k_0 and no differences: 32 bits per column, so the
  // last block's zero-width steps sit exactly at the end of the columns, where the scalar slot
  // read still loads the row after its own. The page goes through a file's bytes so that its
  // words have no spare capacity (the sanitizer build catches a read past them).
  constexpr std::uint64_t N = 32;
  constexpr std::uint32_t n = 3;
  const float bound = 1e-3f, step = 2 * bound;
  EncodedPage page;
  page.method = PageMethod::predictive_lanes;
  page.vertex_count = N;
  page.step_count = n;
  page.window = 8;
  page.codebook_size = 2;
  page.times = {0.0, 1.0, 2.0};
  page.value_min = page.value_max = 1000 * step;
  page.bound = bound;
  page.quantiser.step = step;
  page.quantiser.lo = 0;
  page.quantiser.first_width = 16;
  page.lanes = detail::build_lane_blocks(N, n, page.window, page.quantiser.lo, step, bound, page.quantiser.first_width,
                                         [&](std::uint64_t, std::uint64_t count, float* x) {
                                           std::fill(x, x + count * page.window, 1000 * step);
                                         });
  ASSERT_EQ(detail::lane_blocks_error(page, &page.lanes), "");
  ASSERT_EQ(page.lanes.bit_start.back(), 32u);
  validate_page(page);
  SyntheticField f{N, n, std::vector<float>(N * n, 1000 * step), page.times};
  expect_paths_agree(f, n, through_page_bytes(page), "constant blocks ending on a row");
}

TEST(LaneBlocks, WordsStartOnACacheLineAfterAZeroRowTheFileLeavesOut) {
  const auto f = testing::white_noise(200, 24);
  const EncodedPage page = testing::encode(f, 0, 24, CodecParams{}, 1e-3f * f.range());
  ASSERT_EQ(page.method, PageMethod::predictive_lanes);
  const auto aligned = [](const EncodedPage& p) { return reinterpret_cast<std::uintptr_t>(p.lanes.words.data()) % 64 == 0; };
  EXPECT_TRUE(aligned(page));
  for (std::uint64_t i = 0; i < detail::kLaneBlock; ++i) ASSERT_EQ(page.lanes.words[i], 0u) << i;
  const EncodedPage parsed = through_page_bytes(page);
  // The parser rejects bytes after the payload's last table, so the file held the rows alone;
  // the parsed page has its zero row back.
  EXPECT_TRUE(aligned(parsed));
  EXPECT_TRUE(parsed.lanes.words == page.lanes.words);
  EncodedPage no_zero_row = page;
  no_zero_row.lanes.words.erase(no_zero_row.lanes.words.begin(), no_zero_row.lanes.words.begin() + detail::kLaneBlock);
  EXPECT_THROW(validate_page(no_zero_row), Error);
  // The vector decoders read the zero row below a slot in row 0 but shift those bits out: what it
  // holds never reaches a value.
  EncodedPage junk = page;
  std::fill(junk.lanes.words.begin(), junk.lanes.words.begin() + detail::kLaneBlock, 0xA5A5A5A5u);
  std::vector<float> want(200 * 24), got(200 * 24);
  decode_window(page, want.data());
  decode_window(junk, got.data());
  EXPECT_EQ(0, std::memcmp(want.data(), got.data(), want.size() * 4));
}

TEST(LaneBlocks, ValidatePageFindsFaultsInTheTables) {
  const auto f = testing::white_noise(40, 16);  // 3 blocks, the last of 8 lanes
  const EncodedPage good = testing::encode(f, 0, 16, CodecParams{}, 1e-2f * f.range());
  ASSERT_EQ(good.method, PageMethod::predictive_lanes);
  EXPECT_NO_THROW(validate_page(good));
  auto expect_invalid = [](const EncodedPage& bad, const std::string& what) {
    testing::expect_error([&] { validate_page(bad); }, ErrorCode::invalid_argument, {what}, what);
  };
  EncodedPage bad = good;
  bad.lanes.widths[detail::kLaneWidths + 3] = 33;  // block 1's later steps
  expect_invalid(bad, "width over 32 bits at lane block 1");
  bad = good;
  bad.lanes.widths[detail::kLaneWidths + 1] = 33;  // block 1's step 2
  expect_invalid(bad, "width over 32 bits at lane block 1");
  bad = good;
  bad.lanes.transient_ends[1] = 17;  // past the page's 16 steps
  expect_invalid(bad, "transient end outside the window's steps at lane block 1");
  bad = good;
  bad.lanes.transient_ends[2] = 2;  // before step 3
  expect_invalid(bad, "transient end outside the window's steps at lane block 2");
  bad = good;
  bad.lanes.transient_ends[0] = 3;  // no transient steps, so no width for them
  bad.lanes.widths[detail::kLaneWidths * 0 + 2] = 5;
  expect_invalid(bad, "width for a step the page does not have at lane block 0");
  bad = good;
  bad.lanes.transient_ends.pop_back();
  expect_invalid(bad, "lane transient ends holds 2 values; expected 3");
  bad = good;
  bad.lanes.linear[2] |= 0x8000;  // lane 15 of the last block: past vertex 39
  expect_invalid(bad, "predictor or raw flag on a padding lane at lane block 2");
  bad = good;
  bad.lanes.bit_start[1] += 1;
  expect_invalid(bad, "derived lane block offsets do not match");
  bad = good;
  bad.lanes.words.resize(bad.lanes.words.size() - 16);
  expect_invalid(bad, "lane words holds");
  bad = good;
  bad.quantiser.first_width = 40;
  expect_invalid(bad, "first-value width 40");
  if (!good.lanes.exception_steps.empty()) {
    bad = good;
    bad.lanes.exception_steps[0] = 16;  // past the page's steps
    expect_invalid(bad, "exception steps not increasing inside the window");
  }
}

TEST(LaneBlocks, FilesRoundTripAndOlderVersionsCannotHoldThem) {
  const auto f = testing::white_noise(300, 20);
  CodecParams p;
  p.window = 16;
  p.codebook_size = 16;
  p.bound = {BoundKind::range_relative, 1e-2};
  const std::string path = temp_path("lanes.pnbf"), cut = temp_path("lanes_cut.pnbf");
  testing::stream_field(f, path, p, "noise");
  const auto field = CompressedField::open(path);
  ASSERT_EQ(field->format_version(), std::uint32_t(kContainerFormatVersion));
  ASSERT_EQ(field->page(0).method, PageMethod::predictive_lanes);
  field->verify();
  std::vector<float> step(300);
  for (std::uint64_t t = 0; t < 20; ++t) {
    field->read_step(t, step.data());
    for (std::uint64_t v = 0; v < 300; ++v)
      ASSERT_LE(std::fabs(step[v] - f.values[t * 300 + v]), 1e-2 * f.range() * (1 + 1e-6)) << t << "," << v;
  }
  // Every truncated prefix is rejected.
  const auto bytes = testing::read_file(path);
  for (std::size_t size = 0; size < bytes.size(); size += 1 + size / 64) {
    testing::write_file(cut, bytes.data(), size);
    EXPECT_THROW(CompressedField::open(cut)->verify(), Error) << size << " bytes";
  }
  // A file that says version 2 cannot hold such a page: it is corrupt, not a new page kind. One
  // that says version 3 or 4 holds this version's pages in the wrong layout: corrupt too.
  for (const std::uint32_t version : {2u, 3u, 4u}) {
    std::vector<char> older = bytes;
    std::uint32_t header_bytes, crc;
    std::memcpy(&header_bytes, older.data() + 12, 4);
    std::memcpy(older.data() + 8, &version, 4);
    crc = crc32_reference(older.data(), header_bytes - 4);
    std::memcpy(older.data() + header_bytes - 4, &crc, 4);
    testing::write_file(cut, older.data(), older.size());
    EXPECT_THROW(CompressedField::open(cut)->verify(), Error) << "version " << version;
  }
}

// f scaled down and put on a run's start: its first six steps jump further than the rest, so the
// transient steps get a width of their own.
SyntheticField with_run_start(SyntheticField f) {
  constexpr std::uint32_t kStart = 6;
  const float start[kStart] = {0, 30, 10, 40, 5, 25};  // then 20
  const std::uint64_t n = f.vertices;
  for (std::uint64_t v = 0; v < n; ++v)
    for (std::uint32_t t = 0; t < f.steps; ++t) {
      float& x = f.values[std::uint64_t(t) * n + v];
      x = 0.05f * x + (t < kStart ? start[t] : 20.f) * float(1 + v % 5);
    }
  return f;
}
SyntheticField transient_field(std::uint64_t n, std::uint32_t steps) {
  return with_run_start(testing::white_noise(n, steps, 11));
}

// Codes `f`'s first page.step_count steps as page's lane blocks, with its quantiser, in `layout`,
// and derives their tables.
void build_lanes(const SyntheticField& f, EncodedPage& page, detail::LaneLayout layout = detail::LaneLayout::chosen) {
  const std::uint64_t N = f.vertices;
  const std::uint32_t n = page.step_count;
  page.lanes = detail::build_lane_blocks(N, n, page.window, page.quantiser.lo, page.quantiser.step, page.bound, page.quantiser.first_width,
                                         [&](std::uint64_t first, std::uint64_t count, float* x) {
                                           for (std::uint64_t v = 0; v < count; ++v)
                                             for (std::uint32_t t = 0; t < n; ++t)
                                               x[v * page.window + t] = f.values[std::uint64_t(t) * N + first + v];
                                         },
                                         layout);
  EXPECT_EQ(detail::lane_blocks_error(page, &page.lanes), "");
}

// Builds `f`'s first window as lane blocks in `layout`, with the quantiser encode_window chose
// for it.
EncodedPage lane_page(const SyntheticField& f, std::uint32_t n, detail::LaneLayout layout) {
  EncodedPage page = testing::encode(f, 0, n, CodecParams{}, 1e-3f * f.range());
  EXPECT_EQ(page.method, PageMethod::predictive_lanes);
  build_lanes(f, page, layout);
  return page;
}

TEST(LaneBlocks, TheTransientStepsTakeAWidthOfTheirOwn) {
  const auto f = transient_field(500, 40);
  const EncodedPage own = lane_page(f, 40, detail::LaneLayout::chosen);
  const EncodedPage to_6 = lane_page(f, 40, detail::LaneLayout::transient_to_6);
  const EncodedPage shared = lane_page(f, 40, detail::LaneLayout::one_after_step_1);
  expect_paths_agree(f, 40, own, "transient end per block");
  expect_paths_agree(f, 40, to_6, "transient steps 2-5");
  expect_paths_agree(f, 40, shared, "one width after step 1");
  // The field's jumps last until step 6 (its step-6 difference is 5 to 25 times the rest), so
  // nearly every block ends its transient steps at 7 with wider slots than the later steps'. The
  // older layouts hold one width for steps 2-5 (and pay for step 6 in the later steps' width or
  // as exception rows), or one for every step after step 1.
  const LaneBlocks& L = own.lanes;
  std::uint64_t at_7 = 0;
  for (std::uint64_t b = 0; b < L.block_count(); ++b) {
    if (L.transient_ends[b] == 7) {
      ++at_7;
      ASSERT_GT(detail::lane_transient_width(L, b), detail::lane_width(L, b)) << b;
    }
    ASSERT_EQ(to_6.lanes.transient_ends[b], 6u) << b;
    ASSERT_EQ(detail::lane_width_2(to_6.lanes, b), detail::lane_transient_width(to_6.lanes, b)) << b;
    ASSERT_EQ(detail::lane_width_2(shared.lanes, b), detail::lane_width(shared.lanes, b)) << b;
    ASSERT_EQ(detail::lane_transient_width(shared.lanes, b), detail::lane_width(shared.lanes, b)) << b;
  }
  EXPECT_GE(at_7 * 10, L.block_count() * 9) << at_7 << " of " << L.block_count() << " blocks end their transient at step 7";
  const std::size_t own_bytes = detail::serialize_page(own, 0).size(), to_6_bytes = detail::serialize_page(to_6, 0).size();
  EXPECT_LT(own_bytes, to_6_bytes);
  EXPECT_LT(to_6_bytes, detail::serialize_page(shared, 0).size());
}

// A window longer than a byte can count: each block's transient end stays within the encoder's
// search (step 64 at most), and the page goes through a file's bytes and decodes on every path.
TEST(LaneBlocks, WindowsLongerThanAByteCountsKeepTheirTransientEnds) {
  const auto f = transient_field(70, 300);  // 4 full blocks and one of 6 lanes
  CodecParams p;
  p.window = 512;
  const EncodedPage page = testing::encode(f, 0, 300, p, 1e-3f * f.range());
  ASSERT_EQ(page.method, PageMethod::predictive_lanes);
  for (std::uint64_t b = 0; b < page.lanes.block_count(); ++b) {
    ASSERT_GE(page.lanes.transient_ends[b], 3u) << b;
    ASSERT_LE(page.lanes.transient_ends[b], 64u) << b;
  }
  expect_paths_agree(f, 300, through_page_bytes(page), "300 of 512 steps");
}

// A field of whole numbers coded exactly (step 1, lo 0) as one window of lane blocks, n steps,
// 56 vertices: block 0 constant; block 1 ramps of slopes 1-3, which the extrapolating predictor
// holds exactly; block 2 constant but for jumps that stay (steps 3, 10 and 25: one lane each, the
// first by 600, which a row holds in fewer bits than a width of 11 for any span of steps); and a
// last block of 8 lanes, ramps and constants. Every step after step 1 takes width 0, block 2's
// jumps are exception rows.
EncodedPage exact_lane_page(SyntheticField& f, std::uint32_t n) {
  const std::uint64_t N = 56;
  f = SyntheticField{N, n, std::vector<float>(N * n), std::vector<double>(n)};
  for (std::uint32_t t = 0; t < n; ++t) {
    f.times[t] = t;
    for (std::uint64_t v = 0; v < N; ++v) {
      const std::uint64_t b = v / 16;
      const float ramp = 100.f + 3.f * float(v) + float(1 + v % 3) * float(t);
      float x = b == 0 ? float(v) : b == 1 ? ramp : b == 2 ? 1000.f + float(v) : v % 2 ? ramp : 2000.f + float(v);
      if (v == 33 && t >= 10) x += 37;
      if ((v == 40 || v == 41) && t >= 25) x -= 50;
      if (v == 35 && t >= 3) x += 600;
      f.values[std::uint64_t(t) * N + v] = x;
    }
  }
  EncodedPage page;
  page.method = PageMethod::predictive_lanes;
  page.step_count = n;
  page.window = 64;
  page.vertex_count = N;
  page.times = f.times;
  page.value_min = 0;
  page.value_max = 2100;
  page.quantiser.lo = 0;
  page.quantiser.step = 1;
  page.bound = 0.5f;
  page.quantiser.first_width = 12;
  build_lanes(f, page);
  return page;
}

// The vector window decoders hold k through a span of width 0 without an exception row (or move
// it by the extrapolating lanes' difference) without reading its slots, and take the rows of a
// span of width 0 alone: the same values as the scalar decoder.
TEST(LaneBlocks, SpansOfWidthZeroHoldOrExtrapolateExactly) {
  for (const std::uint32_t n : {40u, 4u}) {
    SyntheticField f;
    const EncodedPage page = exact_lane_page(f, n);
    const LaneBlocks& L = page.lanes;
    ASSERT_EQ(L.block_count(), 4u);
    for (std::uint64_t b = 0; b < 4; ++b)
      for (const auto& span : detail::lane_step_spans(L, b, n)) ASSERT_EQ(span.width, 0u) << n << " steps, block " << b;
    ASSERT_EQ(L.linear[1], 0xFFFF) << "ramps extrapolate";
    ASSERT_EQ(L.exception_rows[0] + L.exception_rows[1] + L.exception_rows[3], 0u);
    ASSERT_EQ(L.exception_rows[2], n == 40 ? 3u : 1u) << "the jumps are rows";
    expect_paths_agree(f, n, page, "whole numbers, " + std::to_string(n) + " steps");
    std::vector<float> window(f.values.size());
    decode_window(page, window.data());
    EXPECT_EQ(window, f.values) << n << " steps";
  }
}

// Format version 3 held lane blocks with one width for every step after step 1 and with
// offset-binary slots; version 4 with one width for steps 2-5 and one for the rest. Pages in
// those layouts go through either version's bytes and back unchanged.
TEST(LaneBlocks, Version3And4PagesReadBackAsTheyWereWritten) {
  const std::pair<std::uint32_t, detail::LaneLayout> versions[] = {{3, detail::LaneLayout::one_after_step_1},
                                                                   {4, detail::LaneLayout::transient_to_6}};
  for (const auto& [version, layout] : versions)
    for (const std::uint32_t n : {40u, 5u, 3u, 2u}) {
      const std::string what = "version " + std::to_string(version) + ", " + std::to_string(n) + " steps";
      const auto f = transient_field(333, n);
      const EncodedPage page = lane_page(f, n, layout);
      const EncodedPage read = through_page_bytes(page, version);
      ASSERT_EQ(read.lanes.widths, page.lanes.widths) << what;
      ASSERT_EQ(read.lanes.transient_ends, page.lanes.transient_ends) << what;
      ASSERT_TRUE(read.lanes.words == page.lanes.words) << what << ": slots not as written";
      expect_paths_agree(f, n, read, what);
      EXPECT_EQ(detail::serialize_page(read, 0, version), detail::serialize_page(page, 0, version)) << what;
    }
  // A page whose blocks choose their transient ends has no version-3 or -4 form, nor does a page
  // with steps 2-5 at a width of their own in version 3.
  const auto f = transient_field(333, 40);
  const EncodedPage chosen = lane_page(f, 40, detail::LaneLayout::chosen);
  for (const std::uint32_t version : {3u, 4u})
    testing::expect_error([&] { detail::serialize_page(chosen, 0, version); }, ErrorCode::invalid_argument,
                          {"format version " + std::to_string(version) + " cannot hold"}, "chosen transient ends");
  testing::expect_error([&] { detail::serialize_page(lane_page(f, 40, detail::LaneLayout::transient_to_6), 0, 3); },
                        ErrorCode::invalid_argument, {"format version 3 cannot hold"}, "steps 2-5 in version 3");
}

// A file the build of format version `version` wrote, read bit for bit as that build read it
// (the values it decoded) with every decoder, and within the bound of its source.
void expect_older_file_reads(const std::string& name, std::uint32_t version, const SyntheticField& source) {
  VectorDecodeGuard guard;
  const std::string dir = PNB_COMPRESSION_TEST_DATA;
  const auto field = CompressedField::open(dir + "/" + name + ".pnbf");
  ASSERT_EQ(field->format_version(), version);
  field->verify();
  const std::uint64_t N = source.vertices;
  const auto expected = testing::read_file(dir + "/" + name + "_decoded.f32");
  ASSERT_EQ(expected.size(), N * source.steps * 4);
  for (std::size_t page = 0; page < field->page_count(); ++page)
    ASSERT_EQ(field->load_page(page)->method, PageMethod::predictive_lanes) << page;
  std::vector<float> step(N);
  for (const auto isa : kEveryLaneIsa) {
    if (!has_lane_isa(isa)) continue;
    for (std::uint64_t t = 0; t < source.steps; ++t) {
      field->read_step(t, step.data());
      ASSERT_EQ(0, std::memcmp(step.data(), expected.data() + t * N * 4, N * 4)) << "decoders up to " << int(isa) << ", step " << t;
      for (std::uint64_t v = 0; v < N; ++v)
        ASSERT_LE(std::fabs(step[v] - source.values[t * N + v]), 1e-2 * source.range() * (1 + 1e-6)) << t << "," << v;
    }
  }
}

// Written by the build of format version 3: white_noise(100, 20, 7) with add_outliers, window
// 16, codebooks of 16, a 1e-2 range-relative bound (two predictive_lanes pages of 16 and 4 steps,
// 28 exception rows).
TEST(LaneBlocks, Version3FilesReadExactlyAsTheirBuildReadThem) {
  auto source = testing::white_noise(100, 20, 7);
  testing::add_outliers(source);
  expect_older_file_reads("lanes_v3", 3, source);
}

// Written by the build of format version 4 with the same codec: with_run_start(white_noise(100,
// 20, 7)) with add_outliers. Page 0 (16 steps) has blocks whose steps 2-5 are wider than the
// rest, and 26 exception rows; page 1 has 4 steps.
TEST(LaneBlocks, Version4FilesReadExactlyAsTheirBuildReadThem) {
  auto source = with_run_start(testing::white_noise(100, 20, 7));
  testing::add_outliers(source);
  expect_older_file_reads("lanes_v4", 4, source);
}

// Written by the build of format version 5 from the same source and codec: its payloads have no
// coding prefix. Page 0 (16 steps) has 20 exception rows, page 1 (4 steps) 4.
TEST(LaneBlocks, Version5FilesReadExactlyAsTheirBuildReadThem) {
  auto source = with_run_start(testing::white_noise(100, 20, 7));
  testing::add_outliers(source);
  expect_older_file_reads("lanes_v5", 5, source);
}

}  // namespace
}  // namespace penumbra::compression
