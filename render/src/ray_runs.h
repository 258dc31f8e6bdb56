// SPDX-License-Identifier: BSD-3-Clause
// render/src/ray_runs.h -- each pixel's runs while a frame renders, then as RayRuns
#pragma once
#include <vector>

#include "penumbra/render/renderer.h"

namespace penumbra::render::detail {

/// Each pixel's runs (row-major, top row first), front to back.
using PixelRuns = std::vector<std::vector<RayRun>>;

/// The runs as one array with per-pixel offsets.
RayRuns flatten_runs(const PixelRuns& pixels);

}  // namespace penumbra::render::detail
