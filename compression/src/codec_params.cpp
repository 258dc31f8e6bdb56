// compression/src/codec_params.cpp
#include "penumbra/compression/codec_params.h"

#include "penumbra/compression/encoded_page.h"

namespace penumbra::compression {

const char* to_string(PageMethod method) {
  switch (method) {
    case PageMethod::vq: return "vq";
    case PageMethod::vq_residual: return "vq-residual";
    case PageMethod::predictive: return "predictive";
    case PageMethod::vq_aligned: return "vq-aligned";
    case PageMethod::vq_aligned_residual: return "vq-aligned-residual";
    case PageMethod::predictive_lanes: return "predictive-lanes";
  }
  return "unknown";
}

std::uint64_t EncodedPage::resident_bytes() const {
  return sizeof(EncodedPage) + times.size() * 8 + (c8.size() + cw.size()) * 4 + mean_q.size() * 2 + i8.size() +
         iw.size() + blocks.group_offsets.size() * 8 + blocks.widths.size() + blocks.payload.size() + blocks.section_bits.size() * 4 +
         ca.size() * 4 + ca_q.size() * 2 + shift.size() + ia.size() + lanes.widths.size() + lanes.transient_ends.size() +
         (lanes.linear.size() + lanes.raw.size() + lanes.exception_rows.size() + lanes.exception_steps.size() +
          lanes.exception_lanes.size()) * 2 +
         lanes.exception_bits.size() + (lanes.raw_values.size() + lanes.words.size() + lanes.highs.size()) * 4 +
         (lanes.bit_start.size() + lanes.raw_start.size() + lanes.row_start.size() + lanes.high_start.size()) * 8;
}

}  // namespace penumbra::compression
