// SPDX-License-Identifier: BSD-3-Clause
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
  std::uint64_t bytes = sizeof(EncodedPage);
  for_each_array([&](const auto& a) { bytes += a.size() * sizeof(a[0]); }, *this);
  return bytes;
}

}  // namespace penumbra::compression
