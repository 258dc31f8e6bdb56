// SPDX-License-Identifier: BSD-3-Clause
// compression/src/page_coding.h -- the lossless stage over a page's payload (format version 6 on;
// private).
//
// From version 6 a page's stored payload (what its header's size and checksum cover) is
//   u32 coding (0: stored as it is, 1: one zstd frame), u32 0, u64 payload bytes, then the
//   payload or its frame.
// The payload's bit-packed slots and one-byte indices are fixed-width, so runs of zeros and
// skewed indices are left in them; zstd takes 1.2-1.8x off the 100K-vertex test fields' pages and
// up to 6x off a slowly changing field's predictive pages, at about 1 GB/s to undo.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/compression/codec_params.h"

namespace penumbra::compression::detail {

constexpr std::uint32_t kFirstCodedVersion = 6;
/// The first format version whose pages hold a ValueMap.
constexpr std::uint32_t kFirstMappedVersion = 7;
constexpr std::size_t kCodingPrefixBytes = 16;
enum class PageCoding : std::uint32_t { stored = 0, zstd = 1 };

/// A zstd level CodecParams::entropy_level may take: 0 (pages stored as they are) to
/// kMaxEntropyLevel. The writer, the streaming encoder (before it allocates its buffers) and
/// serialize_page each refuse any other.
inline bool valid_entropy_level(int level) { return level >= 0 && level <= kMaxEntropyLevel; }

/// A frame is kept where it saves at least this part of the payload (an eighth). Undoing it runs
/// at about 1 GB/s, several times slower than reading the stored bytes: a frame saving 3-12 %
/// (the EEG-like field's pages) tripled their load times, and fast playback found its next page
/// not yet loaded.
constexpr std::uint64_t kMinSavingPart = 8;

/// The payload bytes a stored form's prefix (at `stored`, 16 bytes) declares.
std::uint64_t declared_payload_bytes(const std::uint8_t* stored);

/// Turns `page`, whose payload follows kCodingPrefixBytes of room at `prefix_at`, into its stored
/// form: the prefix filled in, and the payload replaced by a zstd frame at `level` where that
/// saves an eighth (never at level 0). A payload kept as it is is not copied.
void code_payload_in_place(std::vector<std::uint8_t>& page, std::size_t prefix_at, int level);

/// The payload of a stored form [stored, stored + stored_bytes): a pointer into `stored` or into
/// `scratch` (grown as needed, never shrunk), and its size in `bytes`. A prefix that declares an
/// unknown coding or more than `max_bytes`, or a frame that is not exactly the declared bytes,
/// throws Error(io_error) beginning with `name`.
const std::uint8_t* decode_coded_payload(const std::uint8_t* stored, std::uint64_t stored_bytes, std::uint64_t max_bytes,
                                         const std::string& name, std::vector<std::uint8_t>& scratch,
                                         std::uint64_t& bytes);

}  // namespace penumbra::compression::detail
