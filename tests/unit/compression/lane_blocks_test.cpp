// tests/unit/compression/lane_blocks_test.cpp -- predictive_lanes pages: the bound at every value
// on hard windows (one or two steps, a partial last block, exceptions, raw lanes), every decode
// path against the window, the table checks, and the file format's version gate.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
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
  for (const auto isa : {detail::LaneIsa::avx512_vbmi2, detail::LaneIsa::avx512, detail::LaneIsa::avx2, detail::LaneIsa::scalar}) {
    detail::cap_lane_isa(isa);
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

// The page as the file holds it, parsed back: its words then have no spare capacity (the
// sanitizer build catches a read past them) and its zero row is the parser's.
EncodedPage through_page_bytes(const EncodedPage& page) {
  const auto bytes = detail::serialize_page(page, 0);
  detail::PageHeader header;
  EXPECT_TRUE(detail::parse_page_header(bytes.data(), header));
  return detail::parse_page_payload(header, bytes.data() + detail::PageHeader::kBytes, page.vertex_count, page.window,
                                    page.codebook_size, "test page", std::uint32_t(PageMethod::predictive_lanes));
}

TEST(LaneBlocks, EveryPathHoldsTheBoundOnHardWindows) {
  auto noise = testing::white_noise(1003, 40);  // 62 full blocks and a last one of 11 lanes
  testing::add_outliers(noise);
  for (const std::uint32_t n : {1u, 2u, 3u, 21u, 40u}) {
    const float bound = 1e-2f * noise.range();
    const auto page = testing::encode(noise, 0, n, CodecParams{}, bound);
    expect_paths_agree(noise, n, page, "noise, " + std::to_string(n) + " steps");
    if (n >= 3) EXPECT_GT(page.lanes.exception_steps.size(), 0u) << "outliers should be exceptions";
  }
  // Fewer vertices than one block.
  const auto few = testing::white_noise(5, 9);
  expect_paths_agree(few, 9, testing::encode(few, 0, 9, CodecParams{}, 1e-2f * few.range()), "5 vertices");
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
  page.step = step;
  page.lo = 0;
  page.first_width = 16;
  page.lanes = detail::build_lane_blocks(N, n, page.window, page.lo, step, bound, page.first_width,
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
  bad.lanes.widths[4] = 33;  // block 1's later steps
  expect_invalid(bad, "width over 32 bits at lane block 1");
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
  bad.first_width = 40;
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
  // A file that says version 2 cannot hold such a page: it is corrupt, not a new page kind.
  std::vector<char> v2 = bytes;
  std::uint32_t header_bytes, crc, version = 2;
  std::memcpy(&header_bytes, v2.data() + 12, 4);
  std::memcpy(v2.data() + 8, &version, 4);
  crc = crc32_reference(v2.data(), header_bytes - 4);
  std::memcpy(v2.data() + header_bytes - 4, &crc, 4);
  testing::write_file(cut, v2.data(), v2.size());
  EXPECT_THROW(CompressedField::open(cut)->verify(), Error);
}

}  // namespace
}  // namespace penumbra::compression
