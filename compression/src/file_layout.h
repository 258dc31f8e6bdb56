// SPDX-License-Identifier: BSD-3-Clause
// compression/src/file_layout.h -- file header and index trailer of a field file (private).
//
//   header   "PNBFIELD", u32 version, u32 header bytes, u64 vertices, u32 window,
//            u32 codebook size, u32 bound kind, u32 name length, f64 bound value, name, u32 CRC
//   pages    64-byte page header (page_format.h) + payload, one per window, in step order
//   index    u32 "PNBI", u32 pages, u64 steps, f32 min, f32 max (version 7 on: f64, through the
//            pages' maps), f64 times[steps],
//            per page 48 bytes (offset, bytes, first step, steps, method, min, max, bound, u32 0;
//            version 6 on: 56, then u64 the payload's bytes once its coding is undone; version 7
//            on: 72, then f64 map offset, f64 map scale), u32 CRC
//   tail     u64 index offset, u64 file size, u32 index bytes, u32 CRC of these 20 bytes, "PNBEND01"
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/compression/field_file.h"
#include "penumbra/compression/version.h"

namespace penumbra::compression::detail {

constexpr char kFileMagic[8] = {'P', 'N', 'B', 'F', 'I', 'E', 'L', 'D'};
constexpr char kTailMagic[8] = {'P', 'N', 'B', 'E', 'N', 'D', '0', '1'};
constexpr std::uint32_t kIndexMagic = 0x49424E50;  // "PNBI"
constexpr std::size_t kHeaderFixedBytes = 48;      // up to the name
constexpr std::size_t kTailBytes = 32;
constexpr std::uint32_t kMaxNameBytes = 4096;

std::vector<std::uint8_t> serialize_header(const FieldInfo& info);
std::vector<std::uint8_t> serialize_index(const std::vector<PageEntry>& pages, const std::vector<double>& times,
                                          double value_min, double value_max,
                                          std::uint32_t format_version = kContainerFormatVersion);
std::vector<std::uint8_t> serialize_tail(std::uint64_t index_offset, std::uint64_t file_size,
                                         std::uint32_t index_bytes);

}  // namespace penumbra::compression::detail
