// SPDX-License-Identifier: BSD-3-Clause
// compression/src/splitmix.h -- SplitMix64, the encoder's deterministic random numbers (private)
#pragma once
#include <cstdint>

namespace penumbra::compression::detail {

/// Advances `state` and returns the next 64 random bits: training samples and the signs of
/// LBG's splits come from it, so a fixed seed gives identical pages.
inline std::uint64_t splitmix(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

}  // namespace penumbra::compression::detail
