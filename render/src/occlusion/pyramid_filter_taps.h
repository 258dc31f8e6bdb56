// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/pyramid_filter_taps.h -- what the CPU and the GPU pyramid builds must
// share exactly: the Gaussian taps of a pass and the opacity cap
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

namespace penumbra::render::detail {

/// Opacity of one cell of length l is capped below 1 so that converting back stays finite:
/// -ln(1e-6) / l = 13.8 / l, a cell that lets through one millionth of the light.
inline constexpr double kMaxOpacity = 1.0 - 1e-6;

/// Normalised Gaussian taps w[k + radius] for k in [-radius, radius], radius ceil(4 sigma), sigma
/// in node units.
inline std::vector<double> gaussian_taps(double sigma_nodes, int& radius) {
  radius = std::max(1, static_cast<int>(std::ceil(4.0 * sigma_nodes)));
  std::vector<double> w(static_cast<std::size_t>(2 * radius + 1));
  double sum = 0;
  for (int k = -radius; k <= radius; ++k) {
    const double x = k / sigma_nodes;
    w[static_cast<std::size_t>(k + radius)] = std::exp(-0.5 * x * x);
    sum += w[static_cast<std::size_t>(k + radius)];
  }
  for (double& v : w) v /= sum;
  return w;
}

}  // namespace penumbra::render::detail
