// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/pre_illumination.cpp -- object-space occlusion volume and per-point fields
#include <chrono>
#include <cmath>
#include <string>

#include "node_grid.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "occlusion/occlusion_internals.h"

namespace penumbra::render {

PreIlluminationVolume::PreIlluminationVolume(const Bounds& bounds, int resolution,
                                             const std::function<double(const Vec3d&)>& value) {
  require(resolution >= 2, "PreIlluminationVolume: resolution = " + std::to_string(resolution) + "; expected >= 2");
  require(!bounds.empty() && std::isfinite(bounds.diagonal()), "PreIlluminationVolume: bounds are empty or not finite");
  require(static_cast<bool>(value), "PreIlluminationVolume: no value function");
  const auto t0 = std::chrono::steady_clock::now();
  m_lo = bounds.lo;
  detail::node_grid(bounds.hi - bounds.lo, resolution, m_dims, m_h);
  const int nx = m_dims[0], ny = m_dims[1];
  m_values.assign(static_cast<std::size_t>(nx) * ny * m_dims[2], 1.0f);
  parallel_for(static_cast<std::size_t>(ny) * m_dims[2], 1, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t r = r0; r < r1; ++r) {
      const int j = static_cast<int>(r % static_cast<std::size_t>(ny)), k = static_cast<int>(r / static_cast<std::size_t>(ny));
      for (int i = 0; i < nx; ++i)
        m_values[static_cast<std::size_t>(i) + static_cast<std::size_t>(nx) * r] =
            static_cast<float>(value({m_lo.x + i * m_h.x, m_lo.y + j * m_h.y, m_lo.z + k * m_h.z}));
    }
  });
  m_build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double PreIlluminationVolume::sample(const Vec3d& p) const {
  return m_values.empty() ? 1.0 : detail::sample_clamped(m_dims, m_lo, m_h, m_values, p);
}

std::vector<float> evaluate_at_points(const TetMesh& mesh, const std::function<double(const Vec3d&)>& value) {
  require(static_cast<bool>(value), "evaluate_at_points: no value function");
  std::vector<char> used(mesh.points.size(), 0);
  for (const auto& t : mesh.tets)
    for (auto v : t) used[static_cast<std::size_t>(v)] = 1;
  std::vector<float> out(mesh.points.size(), 1.0f);
  parallel_for(out.size(), 256, [&](std::size_t p0, std::size_t p1) {
    for (std::size_t p = p0; p < p1; ++p)
      if (used[p]) out[p] = static_cast<float>(value(mesh.points[p]));
  });
  return out;
}

std::vector<float> grey_light_rgb(const std::vector<float>& factor, double scale) {
  std::vector<float> rgb(factor.size() * 3);
  for (std::size_t p = 0; p < factor.size(); ++p)
    rgb[3 * p] = rgb[3 * p + 1] = rgb[3 * p + 2] = static_cast<float>(scale * factor[p]);
  return rgb;
}

}  // namespace penumbra::render
