// SPDX-License-Identifier: BSD-3-Clause
// compression/src/page_format.cpp
#include "page_format.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "byte_io.h"
#include "crc32.h"
#include "lane_blocks.h"
#include "page_checks.h"
#include "page_coding.h"
#include "page_methods.h"
#include "penumbra/core/error.h"
#include "predictive_layout.h"
#include "vertex_section.h"

namespace penumbra::compression::detail {

namespace {

bool has_vq(PageMethod m) { return uses_plain_vq(m); }
bool has_blocks(PageMethod m) { return has_bit_blocks(m); }

// The quantiser of a page with bit blocks or lane blocks: step, lo, first width and a reserved 0.
void put_quantiser(ByteWriter& w, const EncodedPage& p) {
  w.put(p.quantiser.step);
  w.put(p.quantiser.lo);
  w.put(p.quantiser.first_width);
  w.put(std::uint32_t(0));
}

void get_quantiser(ByteReader& r, EncodedPage& p) {
  p.quantiser.step = r.get<float>();
  p.quantiser.lo = r.get<float>();
  p.quantiser.first_width = r.get<std::uint32_t>();
  r.get<std::uint32_t>();
}

// Format versions 3 and 4 stored fewer widths a block and no transient end: version 4 four
// (step 1's, steps 2-5's, the later steps', the high parts'), version 3 three (step 1's, every
// later step's, the high parts'). Their blocks read into this layout with their transient steps
// ending at kOlderLaneTransientEnd, or the window's end.
std::uint64_t older_lane_widths(std::uint32_t version) { return version >= 4 ? 4 : 3; }

void get_lane_layout(ByteReader& r, LaneBlocks& L, std::uint64_t B, std::uint32_t steps, std::uint32_t version) {
  if (version >= 5) {
    r.get_array(L.widths, kLaneWidths * B);
    return r.get_array(L.transient_ends, B);
  }
  const std::uint64_t stored_widths = older_lane_widths(version);
  const std::uint32_t end = std::min(steps, kOlderLaneTransientEnd);
  std::vector<std::uint8_t> stored;
  r.get_array(stored, stored_widths * B);
  L.widths.resize(kLaneWidths * B);
  L.transient_ends.assign(B, std::uint8_t(end));
  for (std::uint64_t b = 0; b < B; ++b) {
    const std::uint8_t* s = stored.data() + stored_widths * b;
    const std::uint8_t early = s[1], later = version >= 4 ? s[2] : end < steps ? s[1] : 0;
    const std::uint8_t widths[kLaneWidths] = {s[0], early, end > 3 ? early : std::uint8_t(0), later, s[stored_widths - 1]};
    std::copy(widths, widths + kLaneWidths, L.widths.begin() + std::ptrdiff_t(kLaneWidths * b));
  }
}

void put_lane_layout(ByteWriter& w, const EncodedPage& p, std::uint32_t version) {
  const LaneBlocks& L = p.lanes;
  if (version >= 5) {
    w.put_array(L.widths);
    return w.put_array(L.transient_ends);
  }
  const std::uint64_t stored_widths = older_lane_widths(version);
  const std::uint32_t n = p.step_count, end = std::min(n, kOlderLaneTransientEnd);
  std::vector<std::uint8_t> stored(stored_widths * L.block_count());
  for (std::uint64_t b = 0; b < L.block_count(); ++b) {
    const std::uint32_t w2 = lane_width_2(L, b), w3 = lane_transient_width(L, b), later = lane_width(L, b);
    const bool fits = L.transient_ends[b] == end && (end <= 3 || w3 == w2) && (version >= 4 || end == n || later == w2);
    if (!fits)
      throw Error(ErrorCode::invalid_argument, "format version " + std::to_string(version) +
                                                   " cannot hold a lane block's widths (block " + std::to_string(b) + ")");
    std::uint8_t* s = stored.data() + stored_widths * b;
    s[0] = lane_width_1(L, b) & 0xFF;
    s[1] = std::uint8_t(w2);
    if (version >= 4) s[2] = std::uint8_t(later);
    s[stored_widths - 1] = lane_exception_width(L, b) & 0xFF;
  }
  w.put_array(stored);
}

// Flips the top bit of every slot after k_0 in the columns `rows` (row 0; the widths' sums must
// fit them): that turns format version 3's offset-binary slots into this version's two's
// complement ones, and back. The high parts stay as they are.
void flip_lane_slot_signs(const EncodedPage& p, std::uint32_t* rows) {
  const LaneBlocks& L = p.lanes;
  std::uint64_t pos = 0;
  for (std::uint64_t b = 0; b < L.block_count(); ++b) {
    pos += p.quantiser.first_width;
    for (std::uint32_t t = 1; t < p.step_count; ++t) {
      const std::uint32_t width = lane_step_width(L, b, t);
      pos += width;
      if (width == 0) continue;
      const std::uint64_t top = pos - 1;
      std::uint32_t* row = rows + (top >> 5) * kLaneBlock;
      for (std::uint64_t l = 0; l < kLaneBlock; ++l) row[l] ^= 1u << (top & 31);
    }
  }
}

// The tables of a predictive_lanes page in their stored order; each variable-length table's
// size follows from those before it (lane_blocks.h), and lane_blocks_error checks the rest.
void read_lane_blocks(ByteReader& r, EncodedPage& p, std::uint32_t version) {
  LaneBlocks& L = p.lanes;
  get_quantiser(r, p);
  if (p.quantiser.first_width < 1 || p.quantiser.first_width > 31) r.fail("first-value width " + std::to_string(p.quantiser.first_width) + " outside 1..31");
  const std::uint64_t B = lane_block_count(p.vertex_count);
  get_lane_layout(r, L, B, p.step_count, version);
  r.get_array(L.linear, B);
  r.get_array(L.raw, B);
  r.get_array(L.exception_rows, B);
  std::uint64_t rows = 0, raw = 0, bits = 0;
  for (std::uint64_t b = 0; b < B; ++b) {
    rows += L.exception_rows[b];
    raw += std::uint64_t(std::popcount(L.raw[b])) * p.step_count;
    if (const char* error = lane_block_layout_error(L, b, p.step_count))
      r.fail(std::string(error) + " at lane block " + std::to_string(b));
    bits += lane_block_bits(L, b, p.quantiser.first_width, p.step_count);
  }
  r.get_array(L.exception_steps, rows);
  r.get_array(L.exception_lanes, rows);
  std::uint64_t high_bits = 0;
  for (std::uint64_t b = 0, at = 0; b < B; ++b)
    for (std::uint32_t e = 0; e < L.exception_rows[b]; ++e, ++at)
      high_bits += std::uint64_t(std::popcount(L.exception_lanes[at])) * lane_exception_width(L, b);
  r.get_array(L.exception_bits, (high_bits + 7) / 8, 8);
  r.get_array(L.raw_values, raw);
  const std::uint64_t words = kLaneBlock * lane_word_rows(bits);
  if (words > r.remaining() / 4) r.fail("ends inside the lane words");
  reserve_on_huge_pages(L.words, kLaneBlock + words);
  L.words.assign(kLaneBlock + words, 0);  // the zero row, then the file's rows
  r.take(L.words.data() + kLaneBlock, words * 4);
  if (version < 4) flip_lane_slot_signs(p, L.words.data() + kLaneBlock);
}

// Sets every field of `page` to its default, its arrays empty but keeping their memory.
void reset_keeping_memory(EncodedPage& page) {
  EncodedPage fresh;
  for_each_array(
      [](auto& to, auto& from) {
        from.clear();
        to.swap(from);
      },
      fresh, page);
  page = std::move(fresh);
}

// More than the payload of any valid page of N vertices, n steps and codebooks of K entries can
// take, what a compressed payload may declare. The largest per value is a lane page's: a raw
// float, a slot and an exception's high part of up to 32 bits each, and an exception row's 4
// bytes shared by 16 lanes; 16 bytes per value covers it.
std::uint64_t max_payload_bytes(std::uint64_t N, std::uint32_t W, std::uint32_t K, std::uint32_t n) {
  return 16 + 8ull * n + 16ull * K * (2ull * W + 8) + (N + kLaneBlock) * (16ull * n + 64) + 4096;
}

}  // namespace

std::uint32_t max_method_of_version(std::uint32_t version) {
  // Version 1 knew vq, vq_residual and predictive; version 2 added the shift-aligned methods,
  // version 3 predictive_lanes (versions 4 and 5 changed its layout).
  if (version >= 3) return kMaxMethod;
  return version >= 2 ? std::uint32_t(PageMethod::vq_aligned_residual) : std::uint32_t(PageMethod::predictive);
}

std::vector<std::uint8_t> serialize_page(const EncodedPage& p, std::uint32_t page_index, std::uint32_t format_version,
                                         int entropy_level) {
  if (std::uint32_t(p.method) > max_method_of_version(format_version) || format_version > std::uint32_t(kContainerFormatVersion))
    throw Error(ErrorCode::invalid_argument, "format version " + std::to_string(format_version) + " cannot hold a page of method " +
                                                 std::to_string(std::uint32_t(p.method)));
  if (!p.map.identity() && format_version < kFirstMappedVersion)
    throw Error(ErrorCode::invalid_argument, "format version " + std::to_string(format_version) +
                                                 " cannot hold a page whose values are offset or scaled");
  if (!p.map.valid()) throw Error(ErrorCode::invalid_argument, "a page's value map needs a finite offset and a power-of-two scale");
  if (!valid_entropy_level(entropy_level))
    throw Error(ErrorCode::invalid_argument, "entropy level " + std::to_string(entropy_level) + " is outside 0.." +
                                                 std::to_string(kMaxEntropyLevel));
  // From version 6 the payload follows room for its coding prefix, filled in below.
  const bool coded = format_version >= kFirstCodedVersion;
  std::vector<std::uint8_t> bytes(PageHeader::kBytes + (coded ? kCodingPrefixBytes : 0), 0);
  ByteWriter w(bytes);
  if (format_version >= kFirstMappedVersion) {
    w.put(p.map.offset);
    w.put(p.map.scale);
  }
  w.put_array(p.times);
  if (has_vq(p.method)) {
    w.put(p.means.lo);
    w.put(p.means.scale);
    w.put_array(p.vq.c8);
    // A partial window stores only the D_W columns of its steps.
    for (std::uint32_t e = 0; e < p.codebook_size; ++e)
      w.append(p.vq.cw.data() + std::size_t(e) * p.window, std::size_t(p.step_count) * 4);
    w.put_array(p.means.q);
    w.put_array(p.vq.i8);
    w.put_array(p.vq.iw);
  }
  if (uses_aligned_vq(p.method)) {
    w.put(p.means.lo);
    w.put(p.means.scale);
    w.put(p.aligned.ca_lo);
    w.put(p.aligned.ca_scale);
    w.put_array(p.aligned.ca_q);
    w.put_array(p.means.q);
    w.put_array(p.aligned.shift);
    w.put_array(p.aligned.ia);
  }
  if (has_blocks(p.method)) {
    put_quantiser(w, p);
    w.put_array(p.blocks.group_offsets);
    w.put_array(p.blocks.widths);
    w.append(p.blocks.payload.data(), p.blocks.group_offsets.back());  // without the read padding
  }
  if (p.method == PageMethod::predictive_lanes) {
    const LaneBlocks& L = p.lanes;
    put_quantiser(w, p);
    put_lane_layout(w, p, format_version);
    w.put_array(L.linear);
    w.put_array(L.raw);
    w.put_array(L.exception_rows);
    w.put_array(L.exception_steps);
    w.put_array(L.exception_lanes);
    w.append(L.exception_bits.data(), L.exception_bits.size() - 8);  // without the read padding
    w.put_array(L.raw_values);
    // Without the zero row (a page reaches here validated; the max only keeps a bad one in bounds).
    const std::size_t words = std::max<std::size_t>(L.words.size(), kLaneBlock) - kLaneBlock;
    if (format_version >= 4) {
      w.append(lane_rows(L), words * 4);
    } else {
      // The slots are flipped back by the widths: they must describe the words.
      if (L.bit_start.size() != L.block_count() + 1 || L.words.size() != lane_words_held(L.bit_start.back()))
        throw Error(ErrorCode::invalid_argument, "lane blocks whose offsets do not match their words");
      std::vector<std::uint32_t> rows(lane_rows(L), lane_rows(L) + words);
      flip_lane_slot_signs(p, rows.data());
      w.append(rows.data(), words * 4);
    }
  }
  if (coded) code_payload_in_place(bytes, PageHeader::kBytes, entropy_level);
  const std::uint64_t payload_bytes = bytes.size() - PageHeader::kBytes;
  std::uint8_t* h = bytes.data();
  auto at = [&](std::size_t offset, const auto& value) { std::memcpy(h + offset, &value, sizeof(value)); };
  at(0, PageHeader::kMagic);
  at(4, page_index);
  at(8, p.first_step);
  at(16, p.step_count);
  at(20, std::uint32_t(p.method));
  at(24, payload_bytes);
  at(32, p.value_min);
  at(36, p.value_max);
  at(40, p.bound);
  at(44, crc32(bytes.data() + PageHeader::kBytes, payload_bytes));
  at(48, p.sample_snr_db);
  at(52, p.vq_bytes_estimate);
  at(56, p.predictive_bytes_estimate);
  at(60, crc32(h, 60));
  return bytes;
}

bool parse_page_header(const std::uint8_t* h, PageHeader& header) {
  std::uint32_t magic, crc;
  std::memcpy(&magic, h, 4);
  std::memcpy(&crc, h + 60, 4);
  if (magic != PageHeader::kMagic || crc != crc32(h, 60)) return false;
  std::memcpy(&header.page_index, h + 4, 4);
  std::memcpy(&header.first_step, h + 8, 8);
  std::memcpy(&header.step_count, h + 16, 4);
  std::memcpy(&header.method, h + 20, 4);
  std::memcpy(&header.payload_bytes, h + 24, 8);
  std::memcpy(&header.value_min, h + 32, 4);
  std::memcpy(&header.value_max, h + 36, 4);
  std::memcpy(&header.bound, h + 40, 4);
  std::memcpy(&header.payload_crc, h + 44, 4);
  std::memcpy(&header.sample_snr_db, h + 48, 4);
  std::memcpy(&header.vq_bytes_estimate, h + 52, 4);
  std::memcpy(&header.predictive_bytes_estimate, h + 56, 4);
  return true;
}

EncodedPage parse_page_payload(const PageHeader& h, const std::uint8_t* payload, std::uint64_t N, std::uint32_t W,
                               std::uint32_t K, const std::string& name, std::uint32_t format_version) {
  EncodedPage p;
  std::vector<std::uint8_t> scratch;
  parse_page_payload(h, payload, N, W, K, name, format_version, p, scratch);
  return p;
}

void parse_page_payload(const PageHeader& h, const std::uint8_t* stored, std::uint64_t N, std::uint32_t W,
                        std::uint32_t K, const std::string& name, std::uint32_t format_version, EncodedPage& p,
                        std::vector<std::uint8_t>& scratch) {
  reset_keeping_memory(p);
  const std::uint8_t* payload = stored;
  std::uint64_t bytes = h.payload_bytes;
  if (format_version >= kFirstCodedVersion)
    payload = decode_coded_payload(stored, h.payload_bytes, max_payload_bytes(N, W, K, std::min(h.step_count, W)), name,
                                   scratch, bytes);
  ByteReader r(payload, bytes, name);
  if (h.method > max_method_of_version(format_version)) r.fail("unknown method " + std::to_string(h.method));
  if (h.step_count < 1 || h.step_count > W) r.fail("step count " + std::to_string(h.step_count) + " outside 1..window");
  p.method = PageMethod(h.method);
  p.first_step = h.first_step;
  p.step_count = h.step_count;
  p.window = W;
  p.codebook_size = K;
  p.vertex_count = N;
  p.value_min = h.value_min;
  p.value_max = h.value_max;
  p.bound = h.bound;
  p.sample_snr_db = h.sample_snr_db;
  p.vq_bytes_estimate = h.vq_bytes_estimate;
  p.predictive_bytes_estimate = h.predictive_bytes_estimate;
  if (format_version >= kFirstMappedVersion) {
    p.map.offset = r.get<double>();
    p.map.scale = r.get<double>();
    if (!p.map.valid()) r.fail("value map is corrupt (offset not finite, or scale not a positive power of two)");
  }
  r.get_array(p.times, h.step_count);
  if (has_vq(p.method)) {
    p.means.lo = r.get<float>();
    p.means.scale = r.get<float>();
    r.get_array(p.vq.c8, std::uint64_t(K) * 8);
    reserve_on_huge_pages(p.vq.cw, std::size_t(K) * W);
    p.vq.cw.assign(std::size_t(K) * W, 0.f);
    for (std::uint32_t e = 0; e < K; ++e) r.take(p.vq.cw.data() + std::size_t(e) * W, std::size_t(h.step_count) * 4);
    r.get_array(p.means.q, N);
    r.get_array(p.vq.i8, N);
    r.get_array(p.vq.iw, N);
  }
  if (uses_aligned_vq(p.method)) {
    if (W > kMaxAlignedWindow) r.fail("shift-aligned page with a window over 256 steps");
    p.means.lo = r.get<float>();
    p.means.scale = r.get<float>();
    p.aligned.ca_lo = r.get<float>();
    p.aligned.ca_scale = r.get<float>();
    const std::uint32_t D = 2 * W - 1;
    r.get_array(p.aligned.ca_q, std::uint64_t(K) * D);
    p.aligned.ca.resize(p.aligned.ca_q.size());
    for (std::size_t i = 0; i < p.aligned.ca_q.size(); ++i) p.aligned.ca[i] = p.aligned.ca_lo + float(p.aligned.ca_q[i]) * p.aligned.ca_scale;
    r.get_array(p.means.q, N);
    r.get_array(p.aligned.shift, N);
    r.get_array(p.aligned.ia, N);
  }
  if (has_blocks(p.method)) {
    get_quantiser(r, p);
    const std::uint64_t groups = (N + BitBlocks::kGroupSize - 1) / BitBlocks::kGroupSize;
    r.get_array(p.blocks.group_offsets, groups + 1);
    r.get_array(p.blocks.widths, (N + 1) / 2);
    if (p.blocks.group_offsets.back() != r.remaining()) r.fail("bit payload size does not match its group table");
    r.get_array(p.blocks.payload, p.blocks.group_offsets.back(), 8);
  }
  if (p.method == PageMethod::predictive_lanes) read_lane_blocks(r, p, format_version);
  if (r.remaining() != 0) r.fail(std::to_string(r.remaining()) + " unexpected bytes after the payload");
  // Value by value, after the bytes: the section walk also derives each section's start.
  const std::string error = p.method == PageMethod::predictive_lanes ? lane_blocks_error(p, &p.lanes)
                                                                     : page_contents_error(p, &p.blocks.section_bits);
  if (!error.empty()) r.fail(error);
}

}  // namespace penumbra::compression::detail
