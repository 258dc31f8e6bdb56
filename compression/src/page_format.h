// SPDX-License-Identifier: BSD-3-Clause
// compression/src/page_format.h -- one window as one page of bytes, and back (private).
//
// Payload, after the 64-byte header (from version 6 after its coding prefix, page_coding.h), in
// this order (little-endian):
//   (version 7)            f64 map offset, f64 map scale (ValueMap: field = offset + scale x stored)
//   f64 times[steps]
//   vq, vq_residual:       f32 mean lo, f32 mean scale, f32 c8[K x 8], f32 cw[K x steps]
//                          (each entry's first `steps` values), u16 mean[N], u8 i8[N], u8 iw[N]
//   vq_aligned(_residual): f32 level lo, f32 level scale, f32 ca lo, f32 ca scale,
//   (version 2)            u16 ca[K x (2W - 1)], u16 level[N], u8 shift[N], u8 entry[N]
//   *_residual, predictive: f32 step, f32 lo, u32 first width, u32 0, u64 group offsets
//                          [groups + 1], 4-bit codes [N], bit payload (vertex_section.h)
//   predictive_lanes:      f32 step, f32 lo, u32 first width, u32 0, then per block of 16
//   (version 3)            vertices (B of them): u8 widths[4 B] (version 3: [3 B], without the
//                          transient width), u16 linear[B], u16 raw[B],
//                          u16 exception rows[B]; per exception row (R): u16 step[R],
//                          u16 lanes[R]; high parts (bits); f32 raw values; u32 words
//                          (lane_blocks.h; each table's size follows from those before it)
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/compression/encoded_page.h"
#include "penumbra/compression/version.h"

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

/// The highest PageMethod a file of format version `version` holds (version 1: 2).
std::uint32_t max_method_of_version(std::uint32_t version);

/// Header + payload bytes of a page, as a file of `format_version` holds it. Only this build's
/// version writes every page; format version 3 holds predictive_lanes pages without a transient
/// width (built with transient_width off). From version 6 the payload goes through zstd at
/// `entropy_level` (0: stored as it is). Throws Error(invalid_argument) for a page the version
/// cannot hold.
std::vector<std::uint8_t> serialize_page(const EncodedPage& page, std::uint32_t page_index,
                                         std::uint32_t format_version = kContainerFormatVersion, int entropy_level = 0);

/// Parses and checks a 64-byte header; false if the magic or its checksum is wrong.
bool parse_page_header(const std::uint8_t* bytes, PageHeader& header);

/// Parses a payload whose checksum was verified (as stored: from version 6 with its coding
/// prefix); every size and index is checked, so a malformed payload throws Error(io_error)
/// naming `page_name` instead of reading out of bounds. `format_version`: the file's, which
/// decides the methods it knows, their layouts and the coding prefix.
EncodedPage parse_page_payload(const PageHeader& header, const std::uint8_t* payload, std::uint64_t vertex_count,
                               std::uint32_t window, std::uint32_t codebook_size, const std::string& page_name,
                               std::uint32_t format_version);

/// The same into `page`, whose arrays keep their memory: parsing page after page into one
/// EncodedPage touches no fresh memory once its arrays are large enough (a first touch costs
/// about 12 us per 4 KiB on a virtual machine, which held page loads to 90-130 MB/s). What
/// `page` held before is gone, also when this throws. A compressed payload is undone into
/// `scratch`, which keeps its memory the same way.
void parse_page_payload(const PageHeader& header, const std::uint8_t* payload, std::uint64_t vertex_count,
                        std::uint32_t window, std::uint32_t codebook_size, const std::string& page_name,
                        std::uint32_t format_version, EncodedPage& page, std::vector<std::uint8_t>& scratch);

}  // namespace penumbra::compression::detail
