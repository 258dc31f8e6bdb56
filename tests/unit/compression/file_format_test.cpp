// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/file_format_test.cpp -- field files: round trip, truncation, corruption.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <set>

#include "penumbra/compression/field_file.h"
#include "penumbra/compression/streaming_encoder.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"
#include "bit_blocks_builder.h"
#include "crc32_reference.h"
#include "page_coding.h"
#include "page_format.h"
#include "value_layout.h"
#include "expect_error.h"
#include "stream_field.h"
#include "temp_path.h"
#include "test_fields.h"

namespace penumbra::compression {
namespace {

using testing::temp_path;

// Writes f with the streaming encoder (window 8, small codebooks keep the file small).
void write_field(const testing::SyntheticField& f, const std::string& path, CodecParams p) {
  testing::stream_field(f, path, p, "temperature");
}

CodecParams small_params(ErrorBound bound = {}) {
  CodecParams p;
  p.window = 8;
  p.codebook_size = 4;
  p.bound = bound;
  return p;
}

TEST(FieldFile, RoundTripKeepsMetadataAndMatchesThePages) {
  const auto f = testing::shock_front(1000, 21);
  const std::string path = temp_path("rt.pnbf");
  CodecParams p;
  p.window = 16;
  p.bound = {BoundKind::range_relative, 1e-3};
  write_field(f, path, p);
  const auto field = CompressedField::open(path);
  EXPECT_EQ(field->info().name, "temperature");
  EXPECT_EQ(field->info().vertex_count, 1000u);
  EXPECT_EQ(field->info().window, 16u);
  EXPECT_EQ(field->info().bound.kind, BoundKind::range_relative);
  EXPECT_EQ(field->step_count(), 21u);
  EXPECT_EQ(field->page_count(), 2u);  // 16 + a partial window of 5
  EXPECT_EQ(field->page(1).step_count, 5u);
  EXPECT_EQ(field->times(), f.times);
  EXPECT_FLOAT_EQ(field->value_max() - field->value_min(), f.range());
  EXPECT_EQ(field->page_of_step(15), 0u);
  EXPECT_EQ(field->page_of_step(16), 1u);
  EXPECT_THROW(field->page_of_step(21), Error);
  field->verify();
  std::vector<float> out(1000);
  for (std::uint32_t t = 0; t < 21; ++t) {
    field->read_step(t, out.data());
    for (std::uint64_t v = 0; v < 1000; ++v)
      ASSERT_LE(std::fabs(out[v] - f.values[t * 1000 + v]), 1e-3 * f.range() * (1 + 1e-6)) << t << "," << v;
  }
  EXPECT_LT(field->file_bytes(), field->raw_bytes());
}

TEST(FieldFile, EveryTruncatedPrefixIsRejectedNamingWhereItBreaks) {
  const auto f = testing::smooth_blobs(40, 20);
  const std::string path = temp_path("full.pnbf"), cut = temp_path("cut.pnbf");
  write_field(f, path, small_params({BoundKind::absolute, 1e-3}));
  const auto bytes = testing::read_file(path);
  const auto field = CompressedField::open(path);
  ASSERT_EQ(field->page_count(), 3u);
  const std::uint64_t first_page = field->page(0).offset;
  for (std::size_t size = 0; size < bytes.size(); ++size) {
    testing::write_file(cut, bytes.data(), size);
    try {
      CompressedField::open(cut);
      ADD_FAILURE() << "prefix of " << size << " bytes accepted";
    } catch (const Error& e) {
      ASSERT_EQ(e.code(), ErrorCode::io_error);
      const std::string msg = e.what();
      if (size > first_page) {
        ASSERT_TRUE(msg.find("page ") != std::string::npos) << size << ": " << msg;
      }
      if (size > first_page && size < field->page(1).offset) {
        ASSERT_TRUE(msg.find("page 0") != std::string::npos) << size << ": " << msg;
      }
    }
  }
  // Recovery keeps exactly the complete pages of a prefix.
  testing::write_file(cut, bytes.data(), field->page(2).offset + 10);
  const auto partial = CompressedField::open(cut, {.recover_incomplete = true});
  EXPECT_EQ(partial->page_count(), 2u);
  EXPECT_EQ(partial->step_count(), 16u);
  std::vector<float> a(40), b(40);
  partial->read_step(9, a.data());
  field->read_step(9, b.data());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * 4));
}

TEST(FieldFile, CorruptBytesAreDetectedAndNamed) {
  const auto f = testing::smooth_blobs(40, 20);
  const std::string path = temp_path("full.pnbf"), bad = temp_path("bad.pnbf");
  write_field(f, path, small_params({BoundKind::absolute, 1e-3}));
  const auto bytes = testing::read_file(path);
  const auto field = CompressedField::open(path);
  // Flip every byte in turn: opening or loading
  // the affected page must fail with an io_error, never crash or decode garbage.
  std::vector<float> out(40);
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    auto copy = bytes;
    copy[i] ^= 0x5A;
    testing::write_file(bad, copy.data(), copy.size());
    bool rejected = false;
    try {
      const auto g = CompressedField::open(bad);
      g->verify();
    } catch (const Error& e) {
      rejected = true;
      EXPECT_EQ(e.code(), ErrorCode::io_error);
      if (i >= field->page(1).offset && i < field->page(2).offset) {
        EXPECT_NE(std::string(e.what()).find("page 1"), std::string::npos) << i << ": " << e.what();
      }
    }
    EXPECT_TRUE(rejected) << "flipped byte " << i << " of " << bytes.size() << " went unnoticed";
  }
}

// Three fields one after another in time, so that a file's pages change method.
testing::SyntheticField one_after_another(const std::vector<testing::SyntheticField>& parts) {
  testing::SyntheticField all{parts[0].vertices, 0, {}, {}};
  for (const auto& part : parts) {
    const double start = all.times.empty() ? 0 : all.times.back() + 1;
    for (double t : part.times) all.times.push_back(start + t);
    all.values.insert(all.values.end(), part.values.begin(), part.values.end());
    all.steps += part.steps;
  }
  return all;
}

TEST(FieldFile, LoadsIntoSharedBuffersMatchFreshLoadsAndReuseTheSparePage) {
  const auto f = one_after_another({testing::smooth_blobs(700, 16), testing::white_noise(700, 16),
                                    testing::shock_front(700, 16), testing::smooth_blobs(700, 5)});
  const std::string path = temp_path("buffers.pnbf");
  write_field(f, path, small_params());
  const auto field = CompressedField::open(path);
  ASSERT_EQ(field->page_count(), 7u);
  std::set<PageMethod> methods;
  for (std::size_t i = 0; i < field->page_count(); ++i) methods.insert(field->page(i).method);
  ASSERT_GE(methods.size(), 2u) << "the pages should change method";
  PageBuffers buffers;
  std::vector<float> fresh_values, reused_values;
  // Forward, then back: each page is parsed into the memory of one of another method, shape or size.
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < field->page_count(); ++i) order.push_back(i);
  for (std::size_t i = field->page_count(); i-- > 0;) order.push_back(i);
  for (const std::size_t i : order) {
    const auto fresh = field->load_page(i);
    const EncodedPage* spare = buffers.spare.get();
    auto reused = field->load_page(i, buffers);
    if (spare) EXPECT_EQ(reused.get(), spare) << "page " << i << " did not reuse the spare page";
    EXPECT_EQ(buffers.spare, nullptr);
    EXPECT_EQ(reused->resident_bytes(), fresh->resident_bytes()) << "page " << i;
    EXPECT_EQ(detail::serialize_page(*reused, std::uint32_t(i)), detail::serialize_page(*fresh, std::uint32_t(i))) << "page " << i;
    fresh_values.resize(fresh->step_count * 700);
    reused_values.resize(fresh_values.size());
    decode_window(*fresh, fresh_values.data());
    decode_window(*reused, reused_values.data());
    ASSERT_EQ(0, std::memcmp(fresh_values.data(), reused_values.data(), fresh_values.size() * 4)) << "page " << i;
    buffers.spare = std::const_pointer_cast<EncodedPage>(std::move(reused));
  }
  // A spare that someone else still holds is left alone.
  const auto held = buffers.spare;
  const std::vector<std::uint8_t> before = detail::serialize_page(*held, 0);
  const auto other = field->load_page(3, buffers);
  EXPECT_NE(other.get(), held.get());
  EXPECT_EQ(detail::serialize_page(*held, 0), before);
}

TEST(FieldFile, ACorruptPageLoadedIntoBuffersIsNamedAndTheBuffersServeTheNextLoad) {
  const auto f = testing::smooth_blobs(300, 24);
  const std::string path = temp_path("buffers-good.pnbf"), bad = temp_path("buffers-bad.pnbf");
  write_field(f, path, small_params({BoundKind::absolute, 1e-3}));
  auto bytes = testing::read_file(path);
  const auto good = CompressedField::open(path);
  bytes[good->page(1).offset + good->page(1).bytes - 5] ^= 0x5A;  // inside page 1's payload
  testing::write_file(bad, bytes.data(), bytes.size());
  const auto field = CompressedField::open(bad);
  PageBuffers buffers;
  buffers.spare = std::const_pointer_cast<EncodedPage>(field->load_page(0, buffers));
  const EncodedPage* spare = buffers.spare.get();
  testing::expect_error([&] { field->load_page(1, buffers); }, ErrorCode::io_error, {"page 1", "checksum"}, "page 1 corrupt");
  EXPECT_EQ(buffers.spare.get(), spare);
  const auto page2 = field->load_page(2, buffers);
  EXPECT_EQ(page2.get(), spare);
  EXPECT_EQ(detail::serialize_page(*page2, 2), detail::serialize_page(*good->load_page(2), 2));
}

TEST(FieldFile, PatchedSectionWithoutExceptionsIsRejected) {
  // A page whose checksum is right but whose bit block holds a patched section (code 14) with no
  // exceptions: the encoder never writes one, and the vector and scalar decoders would differ
  // on it in the sign of a zero, so the parser refuses it, naming the vertex.
  const auto f = testing::smooth_blobs(24, 8);
  CodecParams params = small_params({BoundKind::absolute, 1e-4});
  params.predictive_lanes = false;
  auto page = encode_window(f.values.data(), f.vertices, 8, f.times.data(), 0, params, 1e-4f);
  ASSERT_TRUE(page.method == PageMethod::vq_residual || page.method == PageMethod::vq_aligned_residual ||
              page.method == PageMethod::predictive)
      << to_string(page.method);
  const bool predictive = page.method == PageMethod::predictive;
  const std::uint64_t broken = 5;
  page.blocks = detail::build_bit_blocks(f.vertices, [&](std::uint64_t, std::uint64_t, const auto& encode) {
    encode([&](std::uint64_t vertex, detail::BitWriter& w) -> std::uint32_t {
      if (predictive) {
        w.put(0, 1);                 // predictor: previous value
        w.put(0, page.quantiser.first_width);  // k_0
      }
      if (vertex != broken) return 0;  // all zero: no value bits
      w.put(0, 4);                     // slot width 0
      w.put(0, 4);                     // no exceptions
      w.put(0, 5);                     // exception width
      return detail::kPatchedCode;
    });
  });
  const auto bytes = detail::serialize_page(page, 0, 2);
  detail::PageHeader header;
  ASSERT_TRUE(detail::parse_page_header(bytes.data(), header));
  testing::expect_error(
      [&] {
        detail::parse_page_payload(header, bytes.data() + detail::PageHeader::kBytes, f.vertices, 8, 4, "page 0", 2);
      },
      ErrorCode::io_error, {"vertex 5", "no exceptions"}, "a patched section without exceptions");
}

// FieldWriter checks every page as the reader will (validate_page): a bad page written would
// make the rest of the run unreadable. The refused page leaves the file as it was.
TEST(FieldFile, WriterRefusesAPageTheReaderWouldReject) {
  const auto f = testing::smooth_blobs(50, 16);
  const CodecParams params = small_params();
  const std::string path = temp_path("refused.pnbf");
  FieldInfo info;
  info.name = "t";
  info.vertex_count = f.vertices;
  info.window = params.window;
  info.codebook_size = params.codebook_size;
  FieldWriter w(path, info);
  const auto page0 = encode_window(f.values.data(), f.vertices, 8, f.times.data(), 0, params, 0.f);
  w.write_page(page0);
  const std::uint64_t written = w.bytes_written();
  auto page1 = encode_window(f.values.data() + 8 * f.vertices, f.vertices, 8, f.times.data() + 8, 8, params, 0.f);
  ASSERT_TRUE(page1.method == PageMethod::vq || page1.method == PageMethod::vq_aligned) << to_string(page1.method);
  EncodedPage bad = page1;
  if (bad.method == PageMethod::vq)
    bad.vq.i8[3] = 200;
  else
    bad.aligned.ia[3] = 200;
  testing::expect_error([&] { w.write_page(bad); }, ErrorCode::invalid_argument, {"out of range at vertex 3"},
                        "an out-of-range codebook index");
  EXPECT_EQ(w.bytes_written(), written);
  w.write_page(page1);
  w.finish();
  const auto field = CompressedField::open(path);
  ASSERT_EQ(field->step_count(), 16u);
  std::vector<float> a(f.vertices), b(f.vertices);
  field->read_step(9, a.data());
  decode_step(page1, 1, b.data());
  EXPECT_EQ(a, b);
}

TEST(FieldFile, NotAFieldFileAndMissingFileAreClearErrors) {
  const std::string path = temp_path("junk.pnbf");
  const std::string junk(200, 'x');
  testing::write_file(path, junk.data(), junk.size());
  try {
    CompressedField::open(path);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad magic"), std::string::npos) << e.what();
  }
  EXPECT_THROW(CompressedField::open(temp_path("missing.pnbf")), Error);
}

TEST(FieldFile, UnfinishedRunLeavesARecoverablePartialFile) {
  const auto f = testing::smooth_blobs(300, 40);
  const std::string path = temp_path("run.pnbf");
  {
    StreamingOptions o;
    o.path = path;
    o.vertex_count = 300;
    o.codec = small_params();
    StreamingEncoder enc(o);
    for (std::uint32_t t = 0; t < 27; ++t) enc.push(f.times[t], f.values.data() + t * 300);
    // no finish(): the solver "died"
  }
  EXPECT_THROW(CompressedField::open(path), Error);
  EXPECT_THROW(CompressedField::open(path + ".partial"), Error);
  const auto rec = CompressedField::open(path + ".partial", {.recover_incomplete = true});
  EXPECT_EQ(rec->step_count(), 24u);  // three full windows of 8; the 3 buffered steps are lost
}


// ---- the lossless stage over page payloads (format version 6) -------------------------------

// Windows of 16 steps within 1e-2 of the range: on slowly changing blobs the predictive and
// residual pages' fixed-width slots hold long runs of zeros, which zstd shrinks well.
CodecParams bounded_16_step_windows() {
  CodecParams p;
  p.window = 16;
  p.bound = {BoundKind::range_relative, 1e-2};
  return p;
}

std::uint32_t stored_coding(const std::vector<char>& file, const PageEntry& page) {
  std::uint32_t coding;
  std::memcpy(&coding, file.data() + page.offset + detail::PageHeader::kBytes, 4);
  return coding;
}

TEST(FieldFile, PagesGoThroughZstdOnlyWhereItSavesAnEighthAndDecodeBitForBit) {
  const auto f = testing::smooth_blobs(3000, 40);
  const std::string plain = temp_path("plain.pnbf"), coded = temp_path("coded.pnbf");
  CodecParams p = bounded_16_step_windows();
  p.entropy_level = 0;
  write_field(f, plain, p);
  p.entropy_level = 3;
  write_field(f, coded, p);
  const auto a = CompressedField::open(plain), b = CompressedField::open(coded);
  ASSERT_EQ(a->page_count(), b->page_count());
  const auto a_bytes = testing::read_file(plain), b_bytes = testing::read_file(coded);
  int compressed = 0;
  for (std::size_t i = 0; i < a->page_count(); ++i) {
    EXPECT_EQ(stored_coding(a_bytes, a->page(i)), std::uint32_t(detail::PageCoding::stored)) << i;
    const std::uint32_t coding = stored_coding(b_bytes, b->page(i));
    if (coding == std::uint32_t(detail::PageCoding::zstd)) {
      ++compressed;
      EXPECT_LE(b->page(i).bytes - 80, (a->page(i).bytes - 80) * 7 / 8) << i;  // payloads, without header and prefix
    } else {
      EXPECT_EQ(coding, std::uint32_t(detail::PageCoding::stored)) << i;
      EXPECT_EQ(b->page(i).bytes, a->page(i).bytes) << i;
    }
  }
  EXPECT_EQ(compressed, int(b->page_count())) << "every page of this field should compress";
  EXPECT_LT(double(b->file_bytes()), 0.8 * double(a->file_bytes()));
  std::vector<float> x(f.vertices), y(f.vertices);
  for (std::uint64_t t = 0; t < f.steps; ++t) {
    a->read_step(t, x.data());
    b->read_step(t, y.data());
    ASSERT_EQ(0, std::memcmp(x.data(), y.data(), x.size() * 4)) << "step " << t;
  }
  // A page of white noise at a tight bound does not shrink: it is stored as it is.
  const auto noise = testing::white_noise(64, 8, 3);
  const std::string noisy = temp_path("noise.pnbf");
  CodecParams q = small_params({BoundKind::range_relative, 1e-6});
  write_field(noise, noisy, q);
  const auto n = CompressedField::open(noisy);
  q.entropy_level = 0;
  write_field(noise, plain, q);
  const auto n0 = CompressedField::open(plain);
  for (std::size_t i = 0; i < n->page_count(); ++i) EXPECT_LE(n->page(i).bytes, n0->page(i).bytes) << i;
}

// A well-sealed page (both checksums right) whose coding prefix lies: each lie is named.
TEST(FieldFile, ACodingPrefixThatLiesIsRejectedNamingThePage) {
  const auto f = testing::smooth_blobs(3000, 16);
  const std::string path = temp_path("coded.pnbf"), bad = temp_path("lying.pnbf");
  write_field(f, path, bounded_16_step_windows());
  const auto field = CompressedField::open(path);
  const auto original = testing::read_file(path);
  const PageEntry& page = field->page(0);
  ASSERT_EQ(stored_coding(original, page), std::uint32_t(detail::PageCoding::zstd));
  const std::size_t prefix = page.offset + detail::PageHeader::kBytes;
  std::uint64_t declared;
  std::memcpy(&declared, original.data() + prefix + 8, 8);
  const auto sealed = [&](auto patch) {
    auto bytes = original;
    patch(bytes);
    const std::uint32_t payload_crc = testing::crc32_reference(bytes.data() + prefix, page.bytes - detail::PageHeader::kBytes);
    std::memcpy(bytes.data() + page.offset + 44, &payload_crc, 4);
    const std::uint32_t header_crc = testing::crc32_reference(bytes.data() + page.offset, 60);
    std::memcpy(bytes.data() + page.offset + 60, &header_crc, 4);
    testing::write_file(bad, bytes.data(), bytes.size());
  };
  const auto put32 = [&](std::vector<char>& b, std::size_t at, std::uint32_t v) { std::memcpy(b.data() + at, &v, 4); };
  const auto put64 = [&](std::vector<char>& b, std::size_t at, std::uint64_t v) { std::memcpy(b.data() + at, &v, 8); };
  const struct {
    std::function<void(std::vector<char>&)> patch;
    std::string says;
  } lies[] = {
      {[&](auto& b) { put32(b, prefix, 7); }, "unknown payload coding 7"},
      {[&](auto& b) { put32(b, prefix + 4, 1); }, "nonzero reserved word"},
      {[&](auto& b) { put64(b, prefix + 8, declared + 1); }, "coding prefix does not match the index"},
      {[&](auto& b) { put32(b, prefix, 0); }, "declares " + std::to_string(declared)},  // "stored", but it is not
      {[&](auto& b) { std::memset(b.data() + prefix + 16, 0xA5, 8); }, "does not decompress"},
  };
  for (const auto& lie : lies) {
    sealed(lie.patch);
    testing::expect_error([&] { CompressedField::open(bad)->load_page(0); }, ErrorCode::io_error, {"page 0", lie.says},
                          lie.says);
  }
  // The index agreeing with a lie about the size (a page parsed on its own): the frame decides.
  const std::vector<std::uint8_t> page_bytes(original.begin() + std::ptrdiff_t(page.offset),
                                             original.begin() + std::ptrdiff_t(page.offset + page.bytes));
  detail::PageHeader header;
  ASSERT_TRUE(detail::parse_page_header(page_bytes.data(), header));
  const struct {
    std::uint64_t declares;
    std::string says;
  } sizes[] = {{declared + 1, "holds " + std::to_string(declared) + " bytes, its prefix declares"},
               {declared - 1, "does not decompress"},
               {std::uint64_t(1) << 40, "more than a page of this field can hold"}};
  for (const auto& size : sizes) {
    auto bytes = page_bytes;
    std::memcpy(bytes.data() + detail::PageHeader::kBytes + 8, &size.declares, 8);
    testing::expect_error(
        [&] {
          detail::parse_page_payload(header, bytes.data() + detail::PageHeader::kBytes, f.vertices, 16, 256, "page 0",
                                     kContainerFormatVersion);
        },
        ErrorCode::io_error, {"page 0", size.says}, size.says);
  }
}

TEST(FieldFile, AnEntropyLevelOutside0To19IsRefused) {
  FieldInfo info;
  info.name = "x";
  info.vertex_count = 10;
  for (const int level : {-1, 20})
    testing::expect_error([&] { FieldWriter(temp_path("level.pnbf"), info, level); }, ErrorCode::invalid_argument,
                          {"entropy_level must be 0..19"}, "FieldWriter");
  CodecParams p = small_params();
  p.entropy_level = 42;
  testing::expect_error([&] { write_field(testing::smooth_blobs(10, 8), temp_path("level.pnbf"), p); },
                        ErrorCode::invalid_argument, {"entropy_level must be 0..19, got 42"}, "StreamingEncoder");
}

}  // namespace
}  // namespace penumbra::compression
