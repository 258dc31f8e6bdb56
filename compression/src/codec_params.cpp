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
  }
  return "unknown";
}

std::uint64_t EncodedPage::resident_bytes() const {
  return sizeof(EncodedPage) + times.size() * 8 + (c8.size() + cw.size()) * 4 + mean_q.size() * 2 + i8.size() +
         iw.size() + blocks.group_offsets.size() * 8 + blocks.widths.size() + blocks.payload.size() + blocks.section_bits.size() * 4 +
         ca.size() * 4 + ca_q.size() * 2 + shift.size() + ia.size();
}

}  // namespace penumbra::compression
