// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/aligned_and_step_test.cpp -- shift-aligned VQ pages (format version 2),
// reading version-1 files, and one-step decoding (section offsets, sequential predictive steps).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "penumbra/compression/field_file.h"
#include "penumbra/compression/pager.h"
#include "penumbra/compression/streaming_encoder.h"
#include "penumbra/compression/version.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"
#include "crc32_reference.h"
#include "expect_error.h"
#include "file_layout.h"
#include "page_coding.h"
#include "page_format.h"
#include "stream_field.h"
#include "temp_path.h"
#include "test_fields.h"

namespace penumbra::compression {
namespace {

using testing::crc32_reference;
using testing::SyntheticField;
using testing::temp_path;

double psnr_db(const float* ref, const float* got, std::size_t count, double range) {
  double se = 0;
  for (std::size_t i = 0; i < count; ++i) se += (double(ref[i]) - got[i]) * (double(ref[i]) - got[i]);
  return se > 0 ? 10 * std::log10(range * range / (se / double(count))) : 400.0;
}

double max_abs_error(const float* ref, const float* got, std::size_t count) {
  double m = 0;
  for (std::size_t i = 0; i < count; ++i) m = std::max(m, std::fabs(double(ref[i]) - got[i]));
  return m;
}

// Step, window and vertex decodes of a page agree bit for bit.
void expect_decodes_agree(const EncodedPage& page) {
  const std::uint64_t N = page.vertex_count;
  const std::uint32_t n = page.step_count;
  std::vector<float> all(N * n), step(N), series(n);
  decode_window(page, all.data());
  for (std::uint32_t t = 0; t < n; t += 7) {
    decode_step(page, t, step.data());
    ASSERT_EQ(0, std::memcmp(step.data(), all.data() + std::uint64_t(t) * N, N * 4)) << "step " << t;
  }
  for (std::uint64_t v = 0; v < N; v += 97) {
    decode_vertex(page, v, series.data());
    for (std::uint32_t t = 0; t < n; ++t) ASSERT_EQ(series[t], all[t * N + v]) << v << "," << t;
  }
}

TEST(AlignedVq, MovingFrontIsAlignedAtItsJumpAndBeatsPlainVq) {
  const auto f = testing::relaxing_front(4000, 64);
  CodecParams p;
  const auto aligned = encode(f, 0, 64, p);
  ASSERT_EQ(aligned.method, PageMethod::vq_aligned);
  // Still 4 bytes per vertex: 16-bit level, shift, entry.
  EXPECT_EQ(aligned.means.q.size() * 2 + aligned.aligned.shift.size() + aligned.aligned.ia.size(), 4u * f.vertices);
  EXPECT_TRUE(aligned.vq.i8.empty() && aligned.vq.iw.empty() && aligned.vq.c8.empty());
  p.aligned = false;
  const auto plain = encode(f, 0, 64, p);
  ASSERT_EQ(plain.method, PageMethod::vq);
  std::vector<float> a(f.values.size()), b(f.values.size());
  decode_window(aligned, a.data());
  decode_window(plain, b.data());
  const double pa = psnr_db(f.values.data(), a.data(), a.size(), f.range());
  const double pp = psnr_db(f.values.data(), b.data(), b.size(), f.range());
  // One shape for every arrival step: far better than one entry per step.
  EXPECT_GT(pa, 55.0);
  EXPECT_GT(pa, pp + 10.0) << "aligned " << pa << " dB, plain " << pp << " dB";
  expect_decodes_agree(aligned);
}

TEST(AlignedVq, SmoothFieldKeepsPlainVq) {
  // Nothing jumps: the plain codebooks represent the sample better and the page says so.
  const auto f = testing::smooth_blobs(3000, 64);
  EXPECT_EQ(encode(f, 0, 64, CodecParams{}).method, PageMethod::vq);
}

TEST(AlignedVq, BoundHeldWithAResidualAndDecodesAgree) {
  const auto f = testing::relaxing_front(3000, 64);
  // A small codebook: at 3000 vertices a 256-entry one would outweigh the vertices, and the
  // page would rightly choose the predictive coder.
  CodecParams p;
  p.codebook_size = 32;
  for (double rel : {1e-2, 1e-3}) {
    const float bound = float(rel * f.range());
    const auto page = encode(f, 0, 64, p, bound);
    ASSERT_EQ(page.method, PageMethod::vq_aligned_residual) << "rel " << rel;
    std::vector<float> out(f.values.size());
    decode_window(page, out.data());
    EXPECT_LE(max_abs_error(f.values.data(), out.data(), out.size()), bound) << "rel " << rel;
    expect_decodes_agree(page);
  }
}

TEST(AlignedVq, PartialWindowShiftsStayInsideItsSteps) {
  const auto f = testing::relaxing_front(2000, 20);
  const auto page = encode(f, 0, 20, CodecParams{});
  ASSERT_EQ(page.method, PageMethod::vq_aligned);
  for (auto s : page.aligned.shift) ASSERT_LT(s, 20u);
  // Deterministic for a fixed seed, like the plain codebooks.
  const auto again = encode(f, 0, 20, CodecParams{});
  EXPECT_EQ(page.aligned.ca_q, again.aligned.ca_q);
  EXPECT_EQ(page.aligned.shift, again.aligned.shift);
  EXPECT_EQ(page.aligned.ia, again.aligned.ia);
  EXPECT_EQ(page.means.q, again.means.q);
  std::vector<float> out(f.values.size());
  decode_window(page, out.data());
  EXPECT_GT(psnr_db(f.values.data(), out.data(), out.size(), f.range()), 45.0);
  expect_decodes_agree(page);
}

TEST(AlignedVq, WarmStartFromAStaleCodebookIsRetrainedCold) {
  // The first window sees the front arrive; the second mostly its relaxing tails, which a
  // warm start from the first window's entries represents poorly.
  const auto f = testing::relaxing_front(3000, 128);
  WarmStart warm;
  std::vector<float> out(std::size_t(64) * f.vertices);
  for (std::uint32_t w = 0; w < 2; ++w) {
    const auto page = encode_window(f.values.data() + std::uint64_t(w) * 64 * f.vertices, f.vertices, 64,
                                    f.times.data() + w * 64, w * 64, CodecParams{}, 0, &warm);
    ASSERT_EQ(page.method, PageMethod::vq_aligned) << "window " << w;
    decode_window(page, out.data());
    EXPECT_GT(psnr_db(f.values.data() + std::uint64_t(w) * 64 * f.vertices, out.data(), out.size(), f.range()), 55.0)
        << "window " << w;
  }
}

// ---- files ---------------------------------------------------------------------------------

std::shared_ptr<const CompressedField> write_field(const SyntheticField& f, const std::string& path, CodecParams p) {
  testing::stream_field(f, path, p, "front");
  return CompressedField::open(path);
}

// Rewrites the version in a file's header (offset 8) and the header's checksum.
std::vector<char> with_version(std::vector<char> bytes, std::uint32_t version) {
  std::uint32_t header_bytes, crc;
  std::memcpy(&header_bytes, bytes.data() + 12, 4);
  std::memcpy(&crc, bytes.data() + header_bytes - 4, 4);
  EXPECT_EQ(crc, crc32_reference(bytes.data(), header_bytes - 4)) << "header layout changed";
  std::memcpy(bytes.data() + 8, &version, 4);
  crc = crc32_reference(bytes.data(), header_bytes - 4);
  std::memcpy(bytes.data() + header_bytes - 4, &crc, 4);
  return bytes;
}

// The field's file as a writer of format `version` wrote it: each page in that version's form
// (before version 6 without a coding prefix), the same index.
std::vector<char> written_as_version(const CompressedField& field, std::uint32_t version) {
  std::vector<std::uint8_t> bytes = detail::serialize_header(field.info());
  std::vector<PageEntry> entries;
  for (std::size_t i = 0; i < field.page_count(); ++i) {
    const auto page = detail::serialize_page(*field.load_page(i), std::uint32_t(i), version);
    PageEntry e = field.page(i);
    e.offset = bytes.size();
    e.bytes = page.size();
    e.payload_bytes =
        page.size() - detail::PageHeader::kBytes - (version >= detail::kFirstCodedVersion ? detail::kCodingPrefixBytes : 0);
    entries.push_back(e);
    bytes.insert(bytes.end(), page.begin(), page.end());
  }
  const auto index = detail::serialize_index(entries, field.times(), field.value_min(), field.value_max(), version);
  const std::uint64_t index_offset = bytes.size();
  bytes.insert(bytes.end(), index.begin(), index.end());
  const auto tail = detail::serialize_tail(index_offset, bytes.size() + detail::kTailBytes, std::uint32_t(index.size()));
  bytes.insert(bytes.end(), tail.begin(), tail.end());
  return with_version(std::vector<char>(bytes.begin(), bytes.end()), version);
}

CodecParams small_params(ErrorBound bound = {}) {
  CodecParams p;
  p.window = 16;
  p.codebook_size = 8;
  p.bound = bound;
  return p;
}

TEST(AlignedFile, PagesRoundTripAndPagedEqualsUnpaged) {
  const auto f = testing::relaxing_front(1500, 40);  // pages of 16, 16 and a partial 8
  // Unbounded: with a bound, pages of so few vertices go to the predictive coder.
  CodecParams p = small_params();
  p.codebook_size = 32;
  const auto field = write_field(f, temp_path("aligned.pnbf"), p);
  EXPECT_EQ(field->format_version(), std::uint32_t(kContainerFormatVersion));
  bool any_aligned = false;
  std::string methods;
  for (std::size_t i = 0; i < field->page_count(); ++i) {
    any_aligned |= field->page(i).method == PageMethod::vq_aligned;
    methods += std::string(" ") + to_string(field->page(i).method);
  }
  ASSERT_TRUE(any_aligned) << methods;
  Pager pager(field);
  std::vector<float> a(1500), b(1500);
  std::vector<std::uint64_t> order;
  for (std::uint64_t t = 0; t < 40; ++t) order.push_back(t);
  for (std::uint64_t t : {39, 2, 20, 21, 0, 33}) order.push_back(t);
  for (std::uint64_t t : order) {
    pager.read_step(t, a.data());
    field->read_step(t, b.data());
    ASSERT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * 4)) << "step " << t;
  }
  std::vector<float> all(f.values.size());
  for (std::uint64_t t = 0; t < 40; ++t) field->read_step(t, all.data() + t * 1500);
  EXPECT_GT(psnr_db(f.values.data(), all.data(), all.size(), f.range()), 40.0);
}

TEST(AlignedFile, TruncatedAndCorruptAlignedPagesAreRejected) {
  const auto f = testing::relaxing_front(40, 20);
  const std::string path = temp_path("al.pnbf"), bad = temp_path("al-bad.pnbf");
  CodecParams p = small_params();
  p.codebook_size = 4;  // a small file: every prefix and every byte is tried
  const auto field = write_field(f, path, p);
  ASSERT_EQ(field->page_count(), 2u);
  ASSERT_EQ(field->page(0).method, PageMethod::vq_aligned);
  const auto bytes = testing::read_file(path);
  for (std::size_t size = 0; size < bytes.size(); ++size) {
    testing::write_file(bad, bytes.data(), size);
    ASSERT_THROW(CompressedField::open(bad), Error) << "prefix of " << size << " bytes accepted";
  }
  // Header and index are covered by the FieldFile tests; here every byte of the aligned page.
  const std::size_t page_begin = field->page(0).offset, page_end = page_begin + field->page(0).bytes;
  for (std::size_t i = page_begin; i < page_end; ++i) {
    auto copy = bytes;
    copy[i] ^= 0x5A;
    testing::write_file(bad, copy.data(), copy.size());
    bool rejected = false;
    try {
      CompressedField::open(bad)->verify();
    } catch (const Error& e) {
      rejected = e.code() == ErrorCode::io_error;
    }
    ASSERT_TRUE(rejected) << "flipped byte " << i << " of page 0 went unnoticed";
  }
}

TEST(AlignedFile, AShiftOutsideThePageIsRejectedEvenUnderValidChecksums) {
  // Checksums catch accidents; the parser must still refuse a well-sealed page whose shift
  // points outside its steps (it would read outside the codebook frame).
  const auto f = testing::relaxing_front(40, 16);
  CodecParams p = small_params();
  p.codebook_size = 4;
  p.entropy_level = 0;  // the payload as it is, after its coding prefix
  const std::string path = temp_path("shift.pnbf"), bad = temp_path("shift-bad.pnbf");
  const auto field = write_field(f, path, p);
  ASSERT_EQ(field->page(0).method, PageMethod::vq_aligned);
  auto bytes = testing::read_file(path);
  const std::size_t page = field->page(0).offset, payload = page + 64;
  // The coding prefix, the value map, times, 4 floats, codebook (4 x 31 u16), levels (40 u16),
  // then the shifts.
  const std::size_t shift0 = payload + 16 + 16 + 16 * 8 + 16 + 4 * 31 * 2 + 40 * 2;
  bytes[shift0] = char(16);  // the page has steps 0..15
  const std::uint32_t payload_crc = crc32_reference(bytes.data() + payload, field->page(0).bytes - 64);
  std::memcpy(bytes.data() + page + 44, &payload_crc, 4);
  const std::uint32_t header_crc = crc32_reference(bytes.data() + page, 60);
  std::memcpy(bytes.data() + page + 60, &header_crc, 4);
  testing::write_file(bad, bytes.data(), bytes.size());
  testing::expect_error([&] { CompressedField::open(bad)->load_page(0); }, ErrorCode::io_error,
                        {"shift out of range at vertex 0", "page 0"}, "a shift of 16 in a 16-step page");
}

TEST(AlignedFile, VersionOneFilesStillReadAndCannotHoldAlignedPages) {
  const auto f = testing::relaxing_front(300, 20);
  CodecParams p = small_params({BoundKind::range_relative, 1e-3});
  p.aligned = false;  // the pages a version-1 writer produced
  p.predictive_lanes = false;
  const std::string v2 = temp_path("plain.pnbf"), v1 = temp_path("v1.pnbf");
  const auto current = write_field(f, v2, p);
  const auto v1_bytes = written_as_version(*current, 1);
  testing::write_file(v1, v1_bytes.data(), v1_bytes.size());
  const auto old = CompressedField::open(v1);
  EXPECT_EQ(old->format_version(), 1u);
  std::vector<float> a(300), b(300);
  for (std::uint64_t t = 0; t < 20; ++t) {
    old->read_step(t, a.data());
    current->read_step(t, b.data());
    ASSERT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * 4)) << t;
  }
  // An aligned page in a file that says version 1 is a corrupt file, not a new page kind.
  const std::string al = temp_path("al2.pnbf");
  const auto aligned = write_field(f, al, small_params());
  ASSERT_EQ(aligned->page(0).method, PageMethod::vq_aligned);
  const auto claims_v1 = with_version(written_as_version(*aligned, 2), 1);
  testing::write_file(v1, claims_v1.data(), claims_v1.size());
  EXPECT_THROW(CompressedField::open(v1)->verify(), Error);
  const auto future = with_version(testing::read_file(al), kContainerFormatVersion + 1);
  testing::write_file(v1, future.data(), future.size());
  EXPECT_THROW(CompressedField::open(v1), Error);
}

// ---- one-step decoding ---------------------------------------------------------------------

TEST(StepDecode, SequentialPredictiveStepsEqualRandomAccessOnes) {
  // Noise is coded predictively; a cursor advances each vertex by one prediction per step.
  const auto f = testing::white_noise(3000, 40);
  for (const bool lanes : {true, false}) {
  SCOPED_TRACE(lanes ? "lane blocks" : "per-vertex sections");
  CodecParams params;
  params.predictive_lanes = lanes;
  const auto page = std::make_shared<const EncodedPage>(encode(f, 0, 40, params, 1e-2f * f.range()));
  ASSERT_EQ(page->method, lanes ? PageMethod::predictive_lanes : PageMethod::predictive);
  StepCursor cursor;
  std::vector<float> a(3000), b(3000);
  std::vector<std::uint32_t> order;
  for (std::uint32_t t = 0; t < 40; ++t) order.push_back(t);
  for (std::uint32_t t : {5u, 6u, 7u, 39u, 0u, 1u, 30u, 30u, 31u}) order.push_back(t);
  for (std::uint32_t t : order) {
    cursor.decode(page, t, a.data());
    decode_step(*page, t, b.data());
    ASSERT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * 4)) << "step " << t;
    ASSERT_LE(max_abs_error(f.values.data() + std::uint64_t(t) * 3000, a.data(), 3000), 1e-2 * f.range());
  }
  // A cursor moves to another page by itself.
  const auto other = std::make_shared<const EncodedPage>(encode(f, 0, 40, params, 2e-2f * f.range()));
  cursor.decode(other, 1, a.data());
  decode_step(*other, 1, b.data());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * 4));
  }
}

TEST(StepDecode, PagerPlaysPredictivePagesLikeRandomAccess) {
  const auto f = testing::white_noise(2000, 37);
  for (const bool lanes : {true, false}) {
  SCOPED_TRACE(lanes ? "lane blocks" : "per-vertex sections");
  CodecParams params = small_params({BoundKind::range_relative, 1e-2});
  params.predictive_lanes = lanes;
  const auto field = write_field(f, temp_path("noise.pnbf"), params);
  ASSERT_EQ(field->page(0).method, lanes ? PageMethod::predictive_lanes : PageMethod::predictive);
  Pager pager(field);
  std::vector<float> a(2000), b(2000);
  for (std::uint64_t t : {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 3, 4, 36, 35, 36}) {
    pager.read_step(t, a.data());
    field->read_step(t, b.data());
    ASSERT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * 4)) << "step " << t;
  }
  }
}

TEST(StepDecode, SectionOffsetsMatchAWalkOverEachGroup) {
  // The offsets derived at load (parser) and at encode (builder) agree, and locate sections
  // of every kind: plain, patched (an isolated outlier) and raw (a value too far for 2^20 steps).
  auto f = testing::smooth_blobs(1000, 16);
  f.values[3 * 1000 + 10] += 50.f;  // an outlier: patched section
  f.values[5 * 1000 + 20] = 1e4f;   // beyond any quantised residual (2^20 steps): raw section
  const std::string path = temp_path("sections.pnbf");
  CodecParams sections = small_params({BoundKind::absolute, 1e-3});
  sections.predictive_lanes = false;
  const auto field = write_field(f, path, sections);
  const auto loaded = field->load_page(0);
  ASSERT_NE(loaded->method, PageMethod::vq);  // residual or predictive: both have sections
  WarmStart warm;
  sections.bound = {};
  const auto encoded = encode_window(f.values.data(), 1000, 16, f.times.data(), 0, sections, 1e-3f, &warm);
  ASSERT_EQ(loaded->blocks.section_bits, encoded.blocks.section_bits);
  ASSERT_EQ(loaded->blocks.section_bits.size(), 1000u);
  bool patched = false, raw = false;
  for (std::uint64_t v = 0; v < 1000; ++v) {
    patched |= loaded->blocks.width(v) == 14;
    raw |= loaded->blocks.width(v) == BitBlocks::kRawWidth;
  }
  EXPECT_TRUE(patched);
  EXPECT_TRUE(raw);
  expect_decodes_agree(*loaded);
  std::vector<float> out(1000);
  for (std::uint32_t t = 0; t < 16; ++t) {
    decode_step(*loaded, t, out.data());
    ASSERT_LE(max_abs_error(f.values.data() + t * 1000, out.data(), 1000), 1e-3 * (1 + 1e-6)) << t;
  }
}

}  // namespace
}  // namespace penumbra::compression
