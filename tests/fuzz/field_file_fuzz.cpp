// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/field_file_fuzz.cpp -- the compressed field reader (.pnbf): CompressedField::open on
// the bytes written to a file (with and without recovery of an unfinished file), then every page
// it lists loaded and decoded every way a reader decodes it (step cursor, decode_step,
// decode_vertex, read_step). Each input is read as it is and again with its CRC-32s (header,
// pages, index, tail) and the tail's file size made right, so that mutations get past the
// checksums to the page parsers and decoders. Memory stays bounded: a file whose header claims
// more than kMaxVertices vertices is only opened, and at most kMaxDecodedValues values are
// decoded per input.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "crc32.h"
#include "file_layout.h"
#include "fuzz_util.h"
#include "page_format.h"
#include "penumbra/compression/field_file.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"

namespace {

using namespace penumbra::compression;
using penumbra::fuzz::load;
using penumbra::fuzz::store;

constexpr std::uint64_t kMaxVertices = 4096;
constexpr std::uint64_t kMaxDecodedValues = std::uint64_t(1) << 22;
constexpr std::size_t kMaxPages = 16;

void put_crc(std::vector<std::uint8_t>& b, std::size_t from, std::size_t n, std::size_t at) {
  store<std::uint32_t>(b, at, detail::crc32(b.data() + from, n));
}

/// The same bytes with every checksum that the structure lets us find made right (layout in
/// compression/src/file_layout.h and page_format.h).
std::vector<std::uint8_t> with_checksums(std::vector<std::uint8_t> b) {
  const std::size_t size = b.size();
  if (size < detail::kHeaderFixedBytes + 4 || std::memcmp(b.data(), detail::kFileMagic, 8) != 0) return b;
  const std::uint64_t header_bytes = load<std::uint32_t>(b, 12);
  if (header_bytes < detail::kHeaderFixedBytes + 4 || header_bytes > size) return b;
  constexpr std::size_t kPage = detail::PageHeader::kBytes;
  std::uint64_t pos = header_bytes;
  while (size - pos >= kPage && load<std::uint32_t>(b, pos) == detail::PageHeader::kMagic) {
    const std::uint64_t payload = load<std::uint64_t>(b, pos + 24);
    const bool whole = payload <= size - pos - kPage;
    if (whole) put_crc(b, pos + kPage, payload, pos + 44);
    put_crc(b, pos, 60, pos + 60);
    if (!whole) break;
    pos += kPage + payload;
  }
  if (size - header_bytes >= detail::kTailBytes && std::memcmp(b.data() + size - 8, detail::kTailMagic, 8) == 0) {
    const std::size_t tail = size - detail::kTailBytes;
    store<std::uint64_t>(b, tail + 8, size);
    const std::uint64_t index_offset = load<std::uint64_t>(b, tail);
    const std::uint32_t index_bytes = load<std::uint32_t>(b, tail + 16);
    if (index_bytes >= 4 && index_offset <= tail && index_bytes <= tail - index_offset)
      put_crc(b, index_offset, index_bytes - 4, index_offset + index_bytes - 4);
    put_crc(b, tail, 20, tail + 20);
  }
  put_crc(b, 0, header_bytes - 4, header_bytes - 4);
  return b;
}

[[noreturn]] void bug(const std::string& what) { penumbra::fuzz::fail("field file: " + what); }

/// Loads and decodes what `f` lists, within the budget.
void decode(const CompressedField& f) {
  const std::uint64_t n = f.info().vertex_count;
  if (f.page_count() > 0 && f.page(f.page_count() - 1).first_step + f.page(f.page_count() - 1).step_count != f.step_count())
    bug("the page table does not cover the steps");
  if (n > kMaxVertices) return;
  std::vector<float> out(n), one;
  std::uint64_t budget = kMaxDecodedValues;
  StepCursor cursor;
  for (std::size_t i = 0; i < f.page_count() && i < kMaxPages; ++i) {
    std::shared_ptr<const EncodedPage> page;
    try {
      page = f.load_page(i);
    } catch (const penumbra::Error&) {
      continue;
    }
    if (page->vertex_count != n || page->step_count != f.page(i).step_count || page->times.size() != page->step_count)
      bug("page " + std::to_string(i) + " does not match the file's header or index");
    for (std::uint32_t t = 0; t < page->step_count && budget >= n; ++t, budget -= n) cursor.decode(page, t, out.data());
    cursor.release();
    if (budget >= n) {
      decode_step(*page, page->step_count - 1, out.data());
      budget -= n;
    }
    one.resize(page->step_count);
    decode_vertex(*page, 0, one.data());
    decode_vertex(*page, n - 1, one.data());
  }
  if (f.step_count() > 0 && budget >= n) {
    try {
      f.read_step(f.step_count() - 1, out.data());
    } catch (const penumbra::Error&) {
    }
  }
}

void read(const std::vector<std::uint8_t>& bytes) {
  const std::string path = penumbra::fuzz::temp_dir() + "/field.pnbf";
  penumbra::fuzz::write_file(path, bytes.data(), bytes.size());
  // Recovery loads pages while it opens: only for a header within the budget.
  const bool small = bytes.size() < 24 || load<std::uint64_t>(bytes, 16) <= kMaxVertices;
  for (const bool recover : {false, true}) {
    if (recover && !small) break;
    std::shared_ptr<CompressedField> f;
    try {
      OpenOptions options;
      options.recover_incomplete = recover;
      f = CompressedField::open(path, options);
    } catch (const penumbra::Error& e) {
      penumbra::fuzz::expect_code(e, penumbra::ErrorCode::io_error, "field file: open");
      continue;
    }
    decode(*f);
    break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t> bytes(data, data + size);
  read(bytes);
  const std::vector<std::uint8_t> fixed = with_checksums(bytes);
  if (fixed != bytes) read(fixed);
  return 0;
}
