// compression/src/page_format.cpp
#include "page_format.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "byte_io.h"
#include "crc32.h"
#include "lane_blocks.h"
#include "page_checks.h"
#include "page_methods.h"
#include "predictive_layout.h"
#include "vertex_section.h"

namespace penumbra::compression::detail {

namespace {

bool has_vq(PageMethod m) { return uses_plain_vq(m); }
bool has_blocks(PageMethod m) { return has_bit_blocks(m); }

// The quantiser of a page with bit blocks or lane blocks: step, lo, first width and a reserved 0.
void put_quantiser(ByteWriter& w, const EncodedPage& p) {
  w.put(p.step);
  w.put(p.lo);
  w.put(p.first_width);
  w.put(std::uint32_t(0));
}

void get_quantiser(ByteReader& r, EncodedPage& p) {
  p.step = r.get<float>();
  p.lo = r.get<float>();
  p.first_width = r.get<std::uint32_t>();
  r.get<std::uint32_t>();
}

// The tables of a predictive_lanes page in their stored order; each variable-length table's
// size follows from those before it (lane_blocks.h), and lane_blocks_error checks the rest.
void read_lane_blocks(ByteReader& r, EncodedPage& p) {
  LaneBlocks& L = p.lanes;
  get_quantiser(r, p);
  if (p.first_width < 1 || p.first_width > 31) r.fail("first-value width " + std::to_string(p.first_width) + " outside 1..31");
  const std::uint64_t B = lane_block_count(p.vertex_count);
  r.get_array(L.widths, 3 * B);
  r.get_array(L.linear, B);
  r.get_array(L.raw, B);
  r.get_array(L.exception_rows, B);
  std::uint64_t rows = 0, raw = 0, bits = 0;
  for (std::uint64_t b = 0; b < B; ++b) {
    rows += L.exception_rows[b];
    raw += std::uint64_t(std::popcount(L.raw[b])) * p.step_count;
    const std::uint32_t w1 = lane_width_1(L, b), w = lane_width(L, b);
    if (w1 > 32 || w > 32 || lane_exception_width(L, b) > 32) r.fail("lane block width over 32 bits at block " + std::to_string(b));
    bits += lane_block_bits(p.first_width, w1, w, p.step_count);
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
  L.words.assign(kLaneBlock + words, 0);  // the zero row, then the file's rows
  r.take(L.words.data() + kLaneBlock, words * 4);
}

}  // namespace

std::vector<std::uint8_t> serialize_page(const EncodedPage& p, std::uint32_t page_index) {
  std::vector<std::uint8_t> bytes(PageHeader::kBytes, 0);
  ByteWriter w(bytes);
  w.put_array(p.times);
  if (has_vq(p.method)) {
    w.put(p.mean_lo);
    w.put(p.mean_scale);
    w.put_array(p.c8);
    // A partial window stores only the D_W columns of its steps.
    for (std::uint32_t e = 0; e < p.codebook_size; ++e)
      w.append(p.cw.data() + std::size_t(e) * p.window, std::size_t(p.step_count) * 4);
    w.put_array(p.mean_q);
    w.put_array(p.i8);
    w.put_array(p.iw);
  }
  if (uses_aligned_vq(p.method)) {
    w.put(p.mean_lo);
    w.put(p.mean_scale);
    w.put(p.ca_lo);
    w.put(p.ca_scale);
    w.put_array(p.ca_q);
    w.put_array(p.mean_q);
    w.put_array(p.shift);
    w.put_array(p.ia);
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
    w.put_array(L.widths);
    w.put_array(L.linear);
    w.put_array(L.raw);
    w.put_array(L.exception_rows);
    w.put_array(L.exception_steps);
    w.put_array(L.exception_lanes);
    w.append(L.exception_bits.data(), L.exception_bits.size() - 8);  // without the read padding
    w.put_array(L.raw_values);
    // Without the zero row (a page reaches here validated; the max only keeps a bad one in bounds).
    w.append(lane_rows(L), (std::max<std::size_t>(L.words.size(), kLaneBlock) - kLaneBlock) * 4);
  }
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
                               std::uint32_t K, const std::string& name, std::uint32_t max_method) {
  ByteReader r(payload, h.payload_bytes, name);
  if (h.method > max_method) r.fail("unknown method " + std::to_string(h.method));
  if (h.step_count < 1 || h.step_count > W) r.fail("step count " + std::to_string(h.step_count) + " outside 1..window");
  EncodedPage p;
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
  r.get_array(p.times, h.step_count);
  if (has_vq(p.method)) {
    p.mean_lo = r.get<float>();
    p.mean_scale = r.get<float>();
    r.get_array(p.c8, std::uint64_t(K) * 8);
    p.cw.assign(std::size_t(K) * W, 0.f);
    for (std::uint32_t e = 0; e < K; ++e) r.take(p.cw.data() + std::size_t(e) * W, std::size_t(h.step_count) * 4);
    r.get_array(p.mean_q, N);
    r.get_array(p.i8, N);
    r.get_array(p.iw, N);
  }
  if (uses_aligned_vq(p.method)) {
    if (W > kMaxAlignedWindow) r.fail("shift-aligned page with a window over 256 steps");
    p.mean_lo = r.get<float>();
    p.mean_scale = r.get<float>();
    p.ca_lo = r.get<float>();
    p.ca_scale = r.get<float>();
    const std::uint32_t D = 2 * W - 1;
    r.get_array(p.ca_q, std::uint64_t(K) * D);
    p.ca.resize(p.ca_q.size());
    for (std::size_t i = 0; i < p.ca_q.size(); ++i) p.ca[i] = p.ca_lo + float(p.ca_q[i]) * p.ca_scale;
    r.get_array(p.mean_q, N);
    r.get_array(p.shift, N);
    r.get_array(p.ia, N);
  }
  if (has_blocks(p.method)) {
    get_quantiser(r, p);
    const std::uint64_t groups = (N + BitBlocks::kGroupSize - 1) / BitBlocks::kGroupSize;
    r.get_array(p.blocks.group_offsets, groups + 1);
    r.get_array(p.blocks.widths, (N + 1) / 2);
    if (p.blocks.group_offsets.back() != r.remaining()) r.fail("bit payload size does not match its group table");
    r.get_array(p.blocks.payload, p.blocks.group_offsets.back(), 8);
  }
  if (p.method == PageMethod::predictive_lanes) read_lane_blocks(r, p);
  if (r.remaining() != 0) r.fail(std::to_string(r.remaining()) + " unexpected bytes after the payload");
  // Value by value, after the bytes: the section walk also derives each section's start.
  const std::string error = p.method == PageMethod::predictive_lanes ? lane_blocks_error(p, &p.lanes)
                                                                     : page_contents_error(p, &p.blocks.section_bits);
  if (!error.empty()) r.fail(error);
  return p;
}

}  // namespace penumbra::compression::detail
