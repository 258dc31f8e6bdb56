// SPDX-License-Identifier: BSD-3-Clause
// compression/src/page_checks.h -- a page's contents checked value by value (private).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/compression/encoded_page.h"

namespace penumbra::compression::detail {

/// What makes a page of decodable shape unsafe or ambiguous to decode, or "" when nothing does.
/// The shape is the caller's to check first: require_decodable (validate_page), or arrays read
/// at the sizes it asks for (the parser). The contents: a codebook index or shift out of range,
/// a group table that is not increasing from 0, a predictive first-value width outside 1..31, a
/// non-finite quantisation step, a section that runs past its group or leaves bytes of it
/// unused, a patched section without exceptions or with exceptions out of order, and (with
/// `derive` null) a section_bits entry that is not where the section starts. With `derive`, the
/// section starts are written there instead of compared (a parsed page has none yet).
/// O(vertices + bits).
std::string page_contents_error(const EncodedPage& p, std::vector<std::uint32_t>* derive);

}  // namespace penumbra::compression::detail
