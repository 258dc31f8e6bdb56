// SPDX-License-Identifier: BSD-3-Clause
// compression/src/field_writer.cpp -- writes a field file (header, pages, index), atomically.
#include <cerrno>
#include <cstring>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "byte_io.h"
#include "crc32.h"
#include "file_layout.h"
#include "page_coding.h"
#include "page_format.h"
#include "page_methods.h"
#include "penumbra/compression/field_file.h"
#include "penumbra/compression/version.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"

namespace penumbra::compression {

namespace detail {

std::vector<std::uint8_t> serialize_header(const FieldInfo& info) {
  std::vector<std::uint8_t> bytes;
  ByteWriter w(bytes);
  w.append(kFileMagic, 8);
  w.put(std::uint32_t(kContainerFormatVersion));
  w.put(std::uint32_t(kHeaderFixedBytes + info.name.size() + 4));
  w.put(info.vertex_count);
  w.put(info.window);
  w.put(info.codebook_size);
  w.put(std::uint32_t(info.bound.kind));
  w.put(std::uint32_t(info.name.size()));
  w.put(info.bound.value);
  w.append(info.name.data(), info.name.size());
  w.put(crc32(bytes.data(), bytes.size()));
  return bytes;
}

std::vector<std::uint8_t> serialize_index(const std::vector<PageEntry>& pages, const std::vector<double>& times,
                                          double value_min, double value_max, std::uint32_t format_version) {
  std::vector<std::uint8_t> bytes;
  ByteWriter w(bytes);
  w.put(kIndexMagic);
  w.put(std::uint32_t(pages.size()));
  w.put(std::uint64_t(times.size()));
  const bool mapped = format_version >= kFirstMappedVersion;
  if (mapped) {
    w.put(value_min);
    w.put(value_max);
  } else {
    w.put(float(value_min));
    w.put(float(value_max));
  }
  w.put_array(times);
  for (const PageEntry& p : pages) {
    w.put(p.offset);
    w.put(p.bytes);
    w.put(p.first_step);
    w.put(p.step_count);
    w.put(std::uint32_t(p.method));
    w.put(p.value_min);
    w.put(p.value_max);
    w.put(p.bound);
    w.put(std::uint32_t(0));
    if (format_version >= kFirstCodedVersion) w.put(p.payload_bytes);
    if (mapped) {
      w.put(p.map.offset);
      w.put(p.map.scale);
    }
  }
  w.put(crc32(bytes.data(), bytes.size()));
  return bytes;
}

std::vector<std::uint8_t> serialize_tail(std::uint64_t index_offset, std::uint64_t file_size, std::uint32_t index_bytes) {
  std::vector<std::uint8_t> bytes;
  ByteWriter w(bytes);
  w.put(index_offset);
  w.put(file_size);
  w.put(index_bytes);
  w.put(crc32(bytes.data(), bytes.size()));
  w.append(kTailMagic, 8);
  return bytes;
}

}  // namespace detail

FieldWriter::FieldWriter(const std::string& path, const FieldInfo& info, int entropy_level)
    : m_path(path), m_partial(path + ".partial"), m_info(info), m_entropy_level(entropy_level) {
  require(!path.empty(), "FieldWriter: empty path");
  require(detail::valid_entropy_level(entropy_level),
          "FieldWriter: entropy_level must be 0.." + std::to_string(kMaxEntropyLevel) + ", got " +
              std::to_string(entropy_level));
  require(info.vertex_count >= 1, "FieldWriter: vertex_count must be positive");
  require(detail::valid_window(info.window),
          "FieldWriter: window must be a multiple of 8 in [8, 1024], got " + std::to_string(info.window));
  require(detail::valid_codebook_size(info.codebook_size),
          "FieldWriter: codebook_size must be 2..256, got " + std::to_string(info.codebook_size));
  require(info.name.size() <= detail::kMaxNameBytes, "FieldWriter: field name longer than 4096 bytes");
  m_file = std::fopen(m_partial.c_str(), "wb");
  if (!m_file)
    throw Error(ErrorCode::io_error, "FieldWriter: cannot create '" + m_partial + "': " + std::strerror(errno));
  const auto header = detail::serialize_header(info);
  write_bytes(header.data(), header.size());
}

FieldWriter::~FieldWriter() {
  // Not finished: keep the partial file (its finished pages are recoverable).
  if (m_file) std::fclose(m_file);
}

void FieldWriter::write_bytes(const void* data, std::size_t size) {
  if (std::fwrite(data, 1, size, m_file) != size)
    throw Error(ErrorCode::io_error, "FieldWriter: writing '" + m_partial + "' failed: " + std::strerror(errno));
  m_offset += size;
}

void FieldWriter::write_page(const EncodedPage& page) {
  if (m_finished) throw Error(ErrorCode::invalid_operation, "FieldWriter::write_page: file already finished");
  require(page.vertex_count == m_info.vertex_count && page.window == m_info.window &&
              page.codebook_size == m_info.codebook_size,
          "FieldWriter::write_page: page shape does not match the field");
  require(page.first_step == m_times.size(), "FieldWriter::write_page: page starts at step " +
                                                  std::to_string(page.first_step) + ", expected " +
                                                  std::to_string(m_times.size()));
  validate_page(page);  // a page the reader would reject is not written
  const auto bytes =
      detail::serialize_page(page, std::uint32_t(m_pages.size()), kContainerFormatVersion, m_entropy_level);
  PageEntry entry{m_offset, bytes.size(), page.first_step, page.step_count, page.method,
                  page.value_min, page.value_max, page.bound,
                  detail::declared_payload_bytes(bytes.data() + detail::PageHeader::kBytes), page.map};
  write_bytes(bytes.data(), bytes.size());
  if (std::fflush(m_file) != 0)
    throw Error(ErrorCode::io_error, "FieldWriter: flushing '" + m_partial + "' failed: " + std::strerror(errno));
  // The map's scale is positive: it keeps the order of the stored values.
  const double lo = page.map.value(page.value_min), hi = page.map.value(page.value_max);
  if (m_pages.empty()) m_min = lo, m_max = hi;
  m_min = std::min(m_min, lo);
  m_max = std::max(m_max, hi);
  m_pages.push_back(entry);
  m_times.insert(m_times.end(), page.times.begin(), page.times.end());
}

void FieldWriter::finish() {
  if (m_finished) return;
  const auto index = detail::serialize_index(m_pages, m_times, m_min, m_max);
  const std::uint64_t index_offset = m_offset;
  write_bytes(index.data(), index.size());
  const auto tail =
      detail::serialize_tail(index_offset, m_offset + detail::kTailBytes, std::uint32_t(index.size()));
  write_bytes(tail.data(), tail.size());
  const bool ok = std::fflush(m_file) == 0 && ::fsync(fileno(m_file)) == 0;
  const bool closed = std::fclose(m_file) == 0;
  m_file = nullptr;
  if (!ok || !closed)
    throw Error(ErrorCode::io_error, "FieldWriter: finishing '" + m_partial + "' failed: " + std::strerror(errno));
  if (std::rename(m_partial.c_str(), m_path.c_str()) != 0)
    throw Error(ErrorCode::io_error, "FieldWriter: renaming '" + m_partial + "' to '" + m_path +
                                         "' failed: " + std::strerror(errno));
  m_finished = true;
}

}  // namespace penumbra::compression
