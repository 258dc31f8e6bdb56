// SPDX-License-Identifier: BSD-3-Clause
// render/src/ray_runs.cpp
#include "ray_runs.h"

#include <cstdint>
#include <cstdio>
#include <string>

#include "penumbra/core/error.h"

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

bool RunsBudget::add(std::size_t runs) {
  const std::size_t total = m_runs.fetch_add(runs, std::memory_order_relaxed) + runs;
  return bytes(total) <= m_budget;
}

bool RunsBudget::add(const PixelRuns& pixels, std::size_t first, std::size_t last) {
  std::size_t runs = 0;
  for (std::size_t p = first; p < last; ++p) runs += pixels[p].size();
  return add(runs);
}

void RunsBudget::check(const char* call) const {
  const std::size_t need = bytes(m_runs.load(std::memory_order_relaxed));
  if (need <= m_budget) return;
  auto mib = [](std::size_t b) {
    char text[32];
    std::snprintf(text, sizeof text, "%.2f", static_cast<double>(b) / (1 << 20));
    return std::string(text);
  };
  throw Error(ErrorCode::out_of_memory,
              std::string(call) + ": the ray runs of this view need at least " + mib(need) + " MiB (" +
                  std::to_string(m_runs.load(std::memory_order_relaxed)) + " runs counted before stopping, over " +
                  std::to_string(m_pixels) + " pixels), more than ray_runs_memory_bytes = " + mib(m_budget) +
                  " MiB; raise it, render smaller images, or give each rank cells that lie together");
}

}  // namespace penumbra::render::detail
