// compression/src/page_format.h -- one window as one page of bytes, and back (private).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/compression/encoded_page.h"

namespace penumbra::compression::detail {

/// Fixed page header, 64 bytes, ahead of every page's payload.
struct PageHeader {
  static constexpr std::uint32_t kMagic = 0x50424E50;  // "PNBP"
  static constexpr std::size_t kBytes = 64;
  std::uint32_t page_index = 0;
  std::uint64_t first_step = 0;
  std::uint32_t step_count = 0;
  std::uint32_t method = 0;
  std::uint64_t payload_bytes = 0;
  float value_min = 0, value_max = 0, bound = 0;
  std::uint32_t payload_crc = 0;
  float sample_snr_db = 0, vq_bytes_estimate = 0, predictive_bytes_estimate = 0;
};

/// Header + payload bytes of a page.
std::vector<std::uint8_t> serialize_page(const EncodedPage& page, std::uint32_t page_index);

/// Parses and checks a 64-byte header; false if the magic or its checksum is wrong.
bool parse_page_header(const std::uint8_t* bytes, PageHeader& header);

/// Parses a payload whose checksum was verified; every size and index is checked, so a
/// malformed payload throws Error(io_error) naming `page_name` instead of reading out of bounds.
EncodedPage parse_page_payload(const PageHeader& header, const std::uint8_t* payload, std::uint64_t vertex_count,
                               std::uint32_t window, std::uint32_t codebook_size, const std::string& page_name);

}  // namespace penumbra::compression::detail
