// SPDX-License-Identifier: BSD-3-Clause
// compression/include/penumbra/compression/field_file.h
#pragma once
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "penumbra/compression/codec_params.h"
#include "penumbra/compression/encoded_page.h"
#include "penumbra/compression/value_map.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::compression {

/// What a compressed field file says about its field (the file header).
struct FieldInfo {
  std::string name;
  std::uint64_t vertex_count = 0;
  std::uint32_t window = 64;
  std::uint32_t codebook_size = 256;
  ErrorBound bound;  ///< as requested; each page records the absolute bound it holds
};

/// One page in the file's index.
struct PageEntry {
  std::uint64_t offset = 0;  ///< of the page header
  std::uint64_t bytes = 0;   ///< header + payload
  std::uint64_t first_step = 0;
  std::uint32_t step_count = 0;
  PageMethod method = PageMethod::vq;
  float value_min = 0, value_max = 0, bound = 0;  ///< of the stored values (EncodedPage)
  std::uint64_t payload_bytes = 0;  ///< the payload's once loaded (compressed on disk from format version 6)
  ValueMap map;                     ///< the page's (format version 7; identity before)
};

/// Writes one field's file: versioned header, one page per window, then an index trailer
/// (time values, value range, page table), all under CRC-32 checksums. Pages go to
/// `path + ".partial"` as they come, flushed one by one, so a run that dies keeps every
/// finished page (CompressedField::open with recover_incomplete reads them); finish() adds
/// the index and renames the file into place atomically. Each page's bytes go through zstd at
/// `entropy_level` (CodecParams::entropy_level: 0..19, 0 none).
class FieldWriter {
public:
  FieldWriter(const std::string& path, const FieldInfo& info, int entropy_level = CodecParams{}.entropy_level);
  ~FieldWriter();
  FieldWriter(const FieldWriter&) = delete;
  FieldWriter& operator=(const FieldWriter&) = delete;

  /// Appends the next window; its first step must follow the previous page's last.
  void write_page(const EncodedPage& page);
  /// Writes the index and moves the file to its final path. Idempotent.
  void finish();
  std::uint64_t bytes_written() const { return m_offset; }
  std::size_t page_count() const { return m_pages.size(); }

private:
  void write_bytes(const void* data, std::size_t size);
  std::string m_path, m_partial;
  FieldInfo m_info;
  int m_entropy_level;
  std::FILE* m_file = nullptr;
  std::uint64_t m_offset = 0;
  std::vector<PageEntry> m_pages;
  std::vector<double> m_times;
  double m_min = 0, m_max = 0;  ///< in the field's units
  bool m_finished = false;
};

struct OpenOptions {
  /// Accept a file without its index (a run that did not finish, e.g. `x.pnbf.partial`):
  /// the complete pages before the first damaged or missing byte are used.
  bool recover_incomplete = false;
};

/// Memory that page loads on one thread can share: the bytes of the last page read, and a page
/// that no one else holds, whose arrays the next load fills again. Loading page after page into
/// the same buffers touches no fresh memory once they are large enough. A first touch of a 4 KiB
/// page costs about 12 us on a virtual machine, which held loads of 50-170 MB pages to
/// 90-130 MB/s; Pager keeps one for its background loads.
struct PageBuffers {
  std::vector<std::uint8_t> bytes;
  std::vector<std::uint8_t> payload;  ///< the last page's payload where the file holds it compressed
  std::shared_ptr<EncodedPage> spare;
};

/// A compressed field file opened for random access. Opening checks the header and the index;
/// each page's checksum is checked when the page is loaded. Thread-safe for concurrent
/// load_page/read_step calls.
class CompressedField {
public:
  /// Throws Error(io_error) for a missing, truncated or corrupt file; the message names the
  /// page (or header/index) at fault.
  static std::shared_ptr<CompressedField> open(const std::string& path, const OpenOptions& options = {});
  ~CompressedField();
  CompressedField(const CompressedField&) = delete;
  CompressedField& operator=(const CompressedField&) = delete;

  const FieldInfo& info() const { return m_info; }
  std::uint64_t step_count() const { return m_times.size(); }
  const std::vector<double>& times() const { return m_times; }
  /// The range of the field's values (through each page's map), in double.
  double value_min() const { return m_min; }
  double value_max() const { return m_max; }
  std::size_t page_count() const { return m_pages.size(); }
  const PageEntry& page(std::size_t index) const { return m_pages.at(index); }
  /// Index of the page holding global step t (throws for t >= step_count()).
  std::size_t page_of_step(std::uint64_t step) const;
  std::uint64_t file_bytes() const { return m_file_bytes; }
  /// Container format version the file was written with (1 .. kContainerFormatVersion).
  std::uint32_t format_version() const { return m_version; }
  /// Bytes the field would take uncompressed (float32).
  std::uint64_t raw_bytes() const { return step_count() * m_info.vertex_count * 4; }

  /// Reads, checks and parses one page.
  std::shared_ptr<const EncodedPage> load_page(std::size_t index) const;
  /// The same, reading into buffers.bytes and parsing into buffers.spare if nothing else holds
  /// it (the page returned is then that object, and spare is left empty).
  std::shared_ptr<const EncodedPage> load_page(std::size_t index, PageBuffers& buffers) const;
  /// Unpaged random access: loads the page of step t and decodes all vertices' values into out
  /// (as float32: see narrow_through_map; the double overload keeps what a page's map holds).
  void read_step(std::uint64_t step, float* out) const;
  void read_step(std::uint64_t step, double* out) const;
  /// Loads every page (checksums and structure); throws naming the first bad one.
  void verify() const;

private:
  CompressedField() = default;
  std::string m_path;
  int m_fd = -1;
  FieldInfo m_info;
  std::vector<PageEntry> m_pages;
  std::vector<double> m_times;
  double m_min = 0, m_max = 0;
  std::uint64_t m_file_bytes = 0;
  std::uint32_t m_version = 0;
  bool m_maps_from_pages = false;  ///< while recovery reads the pages of a file without its index
  std::uint32_t max_method() const;
  /// Reads and checks the file header; returns its size.
  std::uint32_t read_header();
  /// Reads the index trailer; false when the file has none (it did not finish) or a damaged one.
  bool read_index(std::uint32_t header_bytes);
  /// Walks the pages of a file without its index to say where it ends or breaks, and with
  /// OpenOptions::recover_incomplete keeps the complete, intact pages before that point.
  void recover_pages(std::uint32_t header_bytes, const OpenOptions& options);
};

}  // namespace penumbra::compression

PNB_PUBLIC_END
