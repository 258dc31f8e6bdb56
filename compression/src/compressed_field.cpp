// SPDX-License-Identifier: BSD-3-Clause
// compression/src/compressed_field.cpp -- opens a field file; checks header, index and pages.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "byte_io.h"
#include "crc32.h"
#include "file_layout.h"
#include "huge_pages.h"
#include "page_coding.h"
#include "page_format.h"
#include "page_methods.h"
#include "penumbra/compression/field_file.h"
#include "penumbra/compression/version.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"

namespace penumbra::compression {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw Error(ErrorCode::io_error, "compressed field '" + path + "': " + what);
}

void read_at(int fd, const std::string& path, std::uint64_t offset, void* out, std::size_t size,
             const std::string& what) {
  auto* p = static_cast<std::uint8_t*>(out);
  while (size > 0) {
    const ssize_t got = ::pread(fd, p, size, off_t(offset));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) fail(path, what + ": read failed at byte " + std::to_string(offset) + ": " +
                                 (got < 0 ? std::strerror(errno) : "unexpected end of file"));
    p += got;
    offset += std::uint64_t(got);
    size -= std::size_t(got);
  }
}

std::string page_name(std::size_t index) { return "page " + std::to_string(index); }

}  // namespace

std::shared_ptr<CompressedField> CompressedField::open(const std::string& path, const OpenOptions& options) {
  std::shared_ptr<CompressedField> f(new CompressedField());
  f->m_path = path;
  f->m_fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (f->m_fd < 0) fail(path, std::string("cannot open: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(f->m_fd, &st) != 0) fail(path, std::string("cannot stat: ") + std::strerror(errno));
  const std::uint64_t size = std::uint64_t(st.st_size);
  f->m_file_bytes = size;

  const std::uint32_t header_bytes = f->read_header();
  if (!f->read_index(header_bytes)) f->recover_pages(header_bytes, options);
  return f;
}

std::uint32_t CompressedField::read_header() {
  const std::string& path = m_path;
  const std::uint64_t size = m_file_bytes;
  if (size < detail::kHeaderFixedBytes + 4)
    fail(path, "truncated inside the file header (" + std::to_string(size) + " bytes)");
  std::uint8_t fixed[detail::kHeaderFixedBytes];
  read_at(m_fd, path, 0, fixed, sizeof fixed, "file header");
  if (std::memcmp(fixed, detail::kFileMagic, 8) != 0) fail(path, "not a Penumbra compressed field (bad magic)");
  detail::ByteReader hr(fixed + 8, sizeof fixed - 8, "compressed field '" + path + "': file header");
  const auto version = hr.get<std::uint32_t>();
  if (version < 1 || version > std::uint32_t(kContainerFormatVersion))
    fail(path, "format version " + std::to_string(version) + " is not supported (this build reads 1 to " +
                   std::to_string(kContainerFormatVersion) + ")");
  m_version = version;
  const auto header_bytes = hr.get<std::uint32_t>();
  FieldInfo& info = m_info;
  info.vertex_count = hr.get<std::uint64_t>();
  info.window = hr.get<std::uint32_t>();
  info.codebook_size = hr.get<std::uint32_t>();
  info.bound.kind = BoundKind(hr.get<std::uint32_t>());
  const auto name_len = hr.get<std::uint32_t>();
  info.bound.value = hr.get<double>();
  if (name_len > detail::kMaxNameBytes || header_bytes != detail::kHeaderFixedBytes + name_len + 4)
    fail(path, "file header is corrupt (name length)");
  if (size < header_bytes) fail(path, "truncated inside the file header (" + std::to_string(size) + " bytes)");
  std::vector<std::uint8_t> header(header_bytes);
  read_at(m_fd, path, 0, header.data(), header_bytes, "file header");
  std::uint32_t header_crc;
  std::memcpy(&header_crc, header.data() + header_bytes - 4, 4);
  if (header_crc != detail::crc32(header.data(), header_bytes - 4)) fail(path, "file header checksum mismatch");
  info.name.assign(reinterpret_cast<const char*>(header.data()) + detail::kHeaderFixedBytes, name_len);
  if (info.vertex_count < 1 || !detail::valid_window(info.window) || !detail::valid_codebook_size(info.codebook_size) ||
      std::uint32_t(info.bound.kind) > 2)
    fail(path, "file header holds invalid parameters");

  return header_bytes;
}

bool CompressedField::read_index(std::uint32_t header_bytes) {
  const std::string& path = m_path;
  const std::uint64_t size = m_file_bytes;
  bool complete = false;
  if (size >= header_bytes + detail::kTailBytes) {
    std::uint8_t tail[detail::kTailBytes];
    read_at(m_fd, path, size - detail::kTailBytes, tail, sizeof tail, "tail");
    std::uint64_t index_offset, file_size;
    std::uint32_t index_bytes, tail_crc;
    std::memcpy(&index_offset, tail, 8);
    std::memcpy(&file_size, tail + 8, 8);
    std::memcpy(&index_bytes, tail + 16, 4);
    std::memcpy(&tail_crc, tail + 20, 4);
    if (std::memcmp(tail + 24, detail::kTailMagic, 8) == 0 && tail_crc == detail::crc32(tail, 20) &&
        file_size == size && index_offset >= header_bytes &&
        index_offset + index_bytes + detail::kTailBytes == size) {
      std::vector<std::uint8_t> index(index_bytes);
      read_at(m_fd, path, index_offset, index.data(), index_bytes, "index");
      std::uint32_t index_crc;
      if (index_bytes < 4) fail(path, "index is corrupt");
      std::memcpy(&index_crc, index.data() + index_bytes - 4, 4);
      if (index_crc != detail::crc32(index.data(), index_bytes - 4)) fail(path, "index checksum mismatch");
      detail::ByteReader ir(index.data(), index_bytes - 4, "compressed field '" + path + "': index");
      if (ir.get<std::uint32_t>() != detail::kIndexMagic) ir.fail("bad index magic");
      const auto pages = ir.get<std::uint32_t>();
      const auto steps = ir.get<std::uint64_t>();
      const bool mapped = m_version >= detail::kFirstMappedVersion;
      m_min = mapped ? ir.get<double>() : ir.get<float>();
      m_max = mapped ? ir.get<double>() : ir.get<float>();
      ir.get_array(m_times, steps);
      std::uint64_t expect_offset = header_bytes, expect_step = 0;
      for (std::uint32_t i = 0; i < pages; ++i) {
        PageEntry e;
        e.offset = ir.get<std::uint64_t>();
        e.bytes = ir.get<std::uint64_t>();
        e.first_step = ir.get<std::uint64_t>();
        e.step_count = ir.get<std::uint32_t>();
        e.method = PageMethod(ir.get<std::uint32_t>());
        e.value_min = ir.get<float>();
        e.value_max = ir.get<float>();
        e.bound = ir.get<float>();
        ir.get<std::uint32_t>();
        const bool coded = m_version >= detail::kFirstCodedVersion;
        if (coded) e.payload_bytes = ir.get<std::uint64_t>();
        if (mapped) {
          e.map.offset = ir.get<double>();
          e.map.scale = ir.get<double>();
        }
        const std::uint64_t min_bytes = detail::PageHeader::kBytes + (coded ? detail::kCodingPrefixBytes : 0);
        if (e.offset != expect_offset || e.first_step != expect_step || e.step_count < 1 ||
            e.step_count > m_info.window || e.bytes < min_bytes || std::uint32_t(e.method) > max_method() ||
            !e.map.valid())
          ir.fail("entry of " + page_name(i) + " is inconsistent");
        if (!coded) e.payload_bytes = e.bytes - detail::PageHeader::kBytes;
        expect_offset += e.bytes;
        expect_step += e.step_count;
        m_pages.push_back(e);
      }
      if (expect_offset != index_offset || expect_step != steps || ir.remaining() != 0)
        ir.fail("page table does not cover the file");
      complete = true;
    }
  }
  return complete;
}

void CompressedField::recover_pages(std::uint32_t header_bytes, const OpenOptions& options) {
  const std::string& path = m_path;
  const std::uint64_t size = m_file_bytes;
  // No valid index: walk the pages to say where the file ends or breaks, and (if asked)
  // keep the complete, intact pages before that point.
  std::uint64_t pos = header_bytes, next_step = 0;
  std::string problem;
  for (std::size_t i = 0;; ++i) {
    if (pos == size) {
      problem = "ends after " + (i ? page_name(i - 1) : std::string("the header")) +
                " without its index: the writer did not finish (truncated, or an unfinished run)";
      break;
    }
    const std::string previous = i ? page_name(i - 1) : std::string("the header");
    std::uint8_t hb[detail::PageHeader::kBytes] = {};
    const std::size_t avail = std::size_t(std::min<std::uint64_t>(size - pos, sizeof hb));
    read_at(m_fd, path, pos, hb, avail, page_name(i));
    std::uint32_t magic = 0;
    if (avail >= 4) std::memcpy(&magic, hb, 4);
    if (magic == detail::kIndexMagic) {
      problem = "the index after " + previous + " is truncated or corrupt (at byte " + std::to_string(pos) + ")";
      break;
    }
    if (avail < detail::PageHeader::kBytes) {
      problem = "truncated inside the header of " + page_name(i) + " (at byte " + std::to_string(pos) + ")";
      break;
    }
    detail::PageHeader h;
    if (!detail::parse_page_header(hb, h)) {
      problem = "header of " + page_name(i) + " is corrupt (at byte " + std::to_string(pos) + ")";
      break;
    }
    if (h.page_index != i || h.first_step != next_step || h.payload_bytes > size - pos - detail::PageHeader::kBytes) {
      problem = h.page_index != i ? "header of " + page_name(i) + " is corrupt (wrong page number)"
                : h.first_step != next_step
                    ? "header of " + page_name(i) + " is corrupt (it starts at step " + std::to_string(h.first_step) +
                          ", not at step " + std::to_string(next_step) + ")"
                    : "truncated inside " + page_name(i) + ": it needs " +
                          std::to_string(detail::PageHeader::kBytes + h.payload_bytes) + " bytes from byte " +
                          std::to_string(pos) + ", the file has " + std::to_string(size - pos);
      break;
    }
    PageEntry e{pos, detail::PageHeader::kBytes + h.payload_bytes, h.first_step, h.step_count,
                PageMethod(h.method), h.value_min, h.value_max, h.bound, h.payload_bytes, ValueMap{}};
    if (options.recover_incomplete) {
      if (m_version >= detail::kFirstCodedVersion && h.payload_bytes >= detail::kCodingPrefixBytes) {
        std::uint8_t prefix[detail::kCodingPrefixBytes];
        read_at(m_fd, path, pos + detail::PageHeader::kBytes, prefix, sizeof prefix, page_name(i));
        e.payload_bytes = detail::declared_payload_bytes(prefix);
      }
      try {
        m_pages.push_back(e);
        m_maps_from_pages = true;  // no index holds this page's map: it is taken from the page
        const auto page = load_page(i);
        m_maps_from_pages = false;
        m_pages.back().map = page->map;
        m_times.insert(m_times.end(), page->times.begin(), page->times.end());
        const double lo = page->map.value(page->value_min), hi = page->map.value(page->value_max);
        if (i == 0) m_min = lo, m_max = hi;
        m_min = std::min(m_min, lo);
        m_max = std::max(m_max, hi);
      } catch (const Error& err) {
        m_maps_from_pages = false;
        m_pages.pop_back();
        problem = err.what();
        break;
      }
    }
    pos += e.bytes;
    next_step += h.step_count;
  }
  if (!options.recover_incomplete) fail(path, problem);
  if (m_pages.empty()) fail(path, "no complete page to recover: " + problem);
}

CompressedField::~CompressedField() {
  if (m_fd >= 0) ::close(m_fd);
}

std::size_t CompressedField::page_of_step(std::uint64_t step) const {
  require(step < step_count(), "CompressedField: step " + std::to_string(step) + " is outside the field's " +
                                   std::to_string(step_count()) + " steps");
  // Pages are full windows except possibly the last, so the page is step / window; the
  // search below also covers files whose pages were cut differently.
  std::size_t lo = 0, hi = m_pages.size();
  while (hi - lo > 1) {
    const std::size_t mid = (lo + hi) / 2;
    (m_pages[mid].first_step <= step ? lo : hi) = mid;
  }
  return lo;
}

std::shared_ptr<const EncodedPage> CompressedField::load_page(std::size_t index) const {
  PageBuffers buffers;
  return load_page(index, buffers);
}

std::shared_ptr<const EncodedPage> CompressedField::load_page(std::size_t index, PageBuffers& buffers) const {
  require(index < m_pages.size(), "CompressedField::load_page: page " + std::to_string(index) +
                                      " is outside the file's " + std::to_string(m_pages.size()) + " pages");
  const PageEntry& e = m_pages[index];
  const std::string name = "compressed field '" + m_path + "': " + page_name(index);
  // Grown, never shrunk: the next page of the field is about as large.
  std::vector<std::uint8_t>& bytes = buffers.bytes;
  if (bytes.size() < e.bytes) {
    detail::reserve_on_huge_pages(bytes, e.bytes);
    bytes.resize(e.bytes);
  }
  read_at(m_fd, m_path, e.offset, bytes.data(), e.bytes, page_name(index));
  detail::PageHeader h;
  if (!detail::parse_page_header(bytes.data(), h)) throw Error(ErrorCode::io_error, name + ": header is corrupt");
  if (h.page_index != index || h.first_step != e.first_step || h.step_count != e.step_count ||
      detail::PageHeader::kBytes + h.payload_bytes != e.bytes || h.method != std::uint32_t(e.method))
    throw Error(ErrorCode::io_error, name + ": header does not match the index");
  const std::uint8_t* payload = bytes.data() + detail::PageHeader::kBytes;
  if (detail::crc32(payload, h.payload_bytes) != h.payload_crc)
    throw Error(ErrorCode::io_error, name + ": checksum mismatch (the page is corrupt)");
  if (m_version >= detail::kFirstCodedVersion && h.payload_bytes >= detail::kCodingPrefixBytes &&
      detail::declared_payload_bytes(payload) != e.payload_bytes)
    throw Error(ErrorCode::io_error, name + ": coding prefix does not match the index");
  std::shared_ptr<EncodedPage> page = std::move(buffers.spare);  // leaves spare empty
  if (!page || page.use_count() != 1) page = std::make_shared<EncodedPage>();
  try {
    detail::parse_page_payload(h, payload, m_info.vertex_count, m_info.window, m_info.codebook_size, name, m_version,
                               *page, buffers.payload);
  } catch (...) {
    buffers.spare = std::move(page);  // its memory still serves the next load
    throw;
  }
  if (m_version >= detail::kFirstMappedVersion && !m_maps_from_pages && !(page->map == e.map)) {
    buffers.spare = std::move(page);
    throw Error(ErrorCode::io_error, name + ": value map does not match the index");
  }
  return page;
}

std::uint32_t CompressedField::max_method() const { return detail::max_method_of_version(m_version); }

void CompressedField::read_step(std::uint64_t step, float* out) const {
  const std::size_t p = page_of_step(step);
  const auto page = load_page(p);
  decode_step(*page, std::uint32_t(step - m_pages[p].first_step), out);
  narrow_through_map(page->map, out, m_info.vertex_count);
}

void CompressedField::read_step(std::uint64_t step, double* out) const {
  const std::size_t p = page_of_step(step);
  const auto page = load_page(p);
  std::vector<float> stored(m_info.vertex_count);
  decode_step(*page, std::uint32_t(step - m_pages[p].first_step), stored.data());
  apply_map(page->map, stored.data(), stored.size(), out);
}

void CompressedField::verify() const {
  for (std::size_t i = 0; i < m_pages.size(); ++i) load_page(i);
}

}  // namespace penumbra::compression
