// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/step_range.cpp -- the --steps selection
#include "step_range.h"

namespace penumbra::replay {
namespace {

std::size_t parse_index(const std::string& text, const std::string& spec) {
  std::size_t used = 0;
  long long v = -1;
  try {
    v = std::stoll(text, &used);
  } catch (const std::exception&) {
  }
  if (used != text.size() || v < 0) throw UsageError("--steps " + spec + ": '" + text + "' is not a step index >= 0");
  return static_cast<std::size_t>(v);
}

}  // namespace

std::pair<std::size_t, std::size_t> step_range(const std::string& spec, std::size_t n) {
  if (spec.empty()) return {0, n};
  const auto colon = spec.find(':');
  std::size_t first = 0, last = n;
  if (colon == std::string::npos) {
    first = parse_index(spec, spec);
    last = first + 1;
  } else {
    if (colon > 0) first = parse_index(spec.substr(0, colon), spec);
    if (colon + 1 < spec.size()) last = parse_index(spec.substr(colon + 1), spec);
  }
  if (first >= last || last > n)
    throw UsageError("--steps " + spec + " selects no valid steps: INPUT has " + std::to_string(n) +
                     " step(s), indices 0.." + std::to_string(n - 1) + " (a:b is half-open)");
  return {first, last};
}

}  // namespace penumbra::replay
