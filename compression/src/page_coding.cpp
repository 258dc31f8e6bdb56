// SPDX-License-Identifier: BSD-3-Clause
// compression/src/page_coding.cpp
#include "page_coding.h"

#include <zstd.h>

#include <cstring>

#include "huge_pages.h"
#include "penumbra/core/error.h"

namespace penumbra::compression::detail {

namespace {

void put_prefix(std::uint8_t* at, PageCoding coding, std::uint64_t bytes) {
  const std::uint32_t words[2] = {std::uint32_t(coding), 0};
  std::memcpy(at, words, 8);
  std::memcpy(at + 8, &bytes, 8);
}

}  // namespace

std::uint64_t declared_payload_bytes(const std::uint8_t* stored) {
  std::uint64_t bytes;
  std::memcpy(&bytes, stored + 8, 8);
  return bytes;
}

void code_payload_in_place(std::vector<std::uint8_t>& page, std::size_t prefix_at, int level) {
  const std::size_t start = prefix_at + kCodingPrefixBytes;
  const std::uint64_t bytes = page.size() - start;
  if (level > 0) {
    // The frame goes into a new page after the same leading bytes, which replaces this one if
    // the frame is kept: the payload is read once and nothing large is copied.
    const std::size_t bound = ZSTD_compressBound(bytes);
    std::vector<std::uint8_t> framed_page(start + bound);
    const std::size_t framed = ZSTD_compress(framed_page.data() + start, bound, page.data() + start, bytes, level);
    if (!ZSTD_isError(framed) && framed <= bytes - bytes / kMinSavingPart) {
      std::memcpy(framed_page.data(), page.data(), prefix_at);
      framed_page.resize(start + framed);
      page.swap(framed_page);
      put_prefix(page.data() + prefix_at, PageCoding::zstd, bytes);
      return;
    }
  }
  put_prefix(page.data() + prefix_at, PageCoding::stored, bytes);
}

const std::uint8_t* decode_coded_payload(const std::uint8_t* stored, std::uint64_t stored_bytes, std::uint64_t max_bytes,
                                         const std::string& name, std::vector<std::uint8_t>& scratch,
                                         std::uint64_t& bytes) {
  const auto fail = [&](const std::string& what) { throw Error(ErrorCode::io_error, name + ": " + what); };
  if (stored_bytes < kCodingPrefixBytes) fail("payload shorter than its 16-byte coding prefix");
  std::uint32_t words[2];
  std::memcpy(words, stored, 8);
  bytes = declared_payload_bytes(stored);
  const std::uint8_t* data = stored + kCodingPrefixBytes;
  const std::uint64_t data_bytes = stored_bytes - kCodingPrefixBytes;
  if (words[1] != 0) fail("coding prefix has a nonzero reserved word");
  if (words[0] == std::uint32_t(PageCoding::stored)) {
    if (bytes != data_bytes)
      fail("stored payload of " + std::to_string(data_bytes) + " bytes declares " + std::to_string(bytes));
    return data;
  }
  if (words[0] != std::uint32_t(PageCoding::zstd)) fail("unknown payload coding " + std::to_string(words[0]));
  if (bytes > max_bytes)
    fail("compressed payload declares " + std::to_string(bytes) + " bytes, more than a page of this field can hold (" +
         std::to_string(max_bytes) + ")");
  if (scratch.size() < bytes) {
    reserve_on_huge_pages(scratch, bytes);
    scratch.resize(bytes);
  }
  const std::size_t got = ZSTD_decompress(scratch.data(), bytes, data, data_bytes);
  if (ZSTD_isError(got)) fail(std::string("compressed payload does not decompress (") + ZSTD_getErrorName(got) + ")");
  if (got != bytes)
    fail("compressed payload holds " + std::to_string(got) + " bytes, its prefix declares " + std::to_string(bytes));
  return scratch.data();
}

}  // namespace penumbra::compression::detail
