// SPDX-License-Identifier: BSD-3-Clause
// render/src/ray_runs.h -- each pixel's runs while a frame renders, then as RayRuns
#pragma once
#include <atomic>
#include <cstdint>
#include <vector>

#include "penumbra/render/renderer.h"

namespace penumbra::render::detail {

/// Each pixel's runs (row-major, top row first), front to back.
using PixelRuns = std::vector<std::vector<RayRun>>;

/// The runs as one array with per-pixel offsets.
RayRuns flatten_runs(const PixelRuns& pixels);

/// A frame's runs counted against RenderOptions::ray_runs_memory_bytes, from any thread.
class RunsBudget {
public:
  static constexpr std::size_t kBytesPerPixel = sizeof(std::vector<RayRun>) + sizeof(std::uint32_t);
  static constexpr std::size_t kBytesPerRun = 2 * sizeof(RayRun);  // the pixel's list, then the flat copy
  RunsBudget(std::size_t budget_bytes, std::size_t pixels) : m_budget(budget_bytes), m_pixels(pixels) {}
  /// Counts `runs` more; false once the frame is over its budget (the rest can be skipped).
  bool add(std::size_t runs);
  /// The runs of `pixels`' [first, last) counted (a tile's rows).
  bool add(const PixelRuns& pixels, std::size_t first, std::size_t last);
  /// Throws Error(out_of_memory) naming `call` when the frame is over its budget.
  void check(const char* call) const;

private:
  std::size_t bytes(std::size_t runs) const { return m_pixels * kBytesPerPixel + runs * kBytesPerRun; }
  std::size_t m_budget, m_pixels;
  std::atomic<std::size_t> m_runs{0};
};

}  // namespace penumbra::render::detail
