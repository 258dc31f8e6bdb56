// SPDX-License-Identifier: BSD-3-Clause
// render/src/ray_runs.cpp
#include "ray_runs.h"

#include <cstdint>

namespace penumbra::render::detail {

RayRuns flatten_runs(const PixelRuns& pixels) {
  RayRuns out;
  out.offsets.reserve(pixels.size() + 1);
  out.offsets.push_back(0);
  for (const auto& pixel : pixels) {
    out.runs.insert(out.runs.end(), pixel.begin(), pixel.end());
    out.offsets.push_back(static_cast<std::uint32_t>(out.runs.size()));
  }
  return out;
}

}  // namespace penumbra::render::detail
