// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/step_range.h -- penumbra-replay's usage errors and its --steps selection
#pragma once
#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>

namespace penumbra::replay {

/// A bad command line: reported with the usage text and exit status 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Half-open range [first, last) of step indices selected by "a:b", "a:", ":b" or "a" among `n`
/// steps (all for an empty spec); throws UsageError for text that is not one or selects none.
std::pair<std::size_t, std::size_t> step_range(const std::string& spec, std::size_t n);

}  // namespace penumbra::replay
