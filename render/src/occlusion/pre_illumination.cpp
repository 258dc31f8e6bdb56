// render/src/occlusion/pre_illumination.cpp -- object-space occlusion volume and per-point fields
#include <chrono>
#include <cmath>
#include <string>

#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "penumbra/render/occlusion.h"

namespace penumbra::render {

PreIlluminationVolume::PreIlluminationVolume(const Bounds& bounds, int resolution,
                                             const std::function<double(const Vec3d&)>& value) {
  require(resolution >= 2, "PreIlluminationVolume: resolution = " + std::to_string(resolution) + "; expected >= 2");
  require(!bounds.empty() && std::isfinite(bounds.diagonal()), "PreIlluminationVolume: bounds are empty or not finite");
  require(static_cast<bool>(value), "PreIlluminationVolume: no value function");
  const auto t0 = std::chrono::steady_clock::now();
  const Vec3d ext = bounds.hi - bounds.lo;
  const double longest = std::max(ext.x, std::max(ext.y, ext.z));
  m_lo = bounds.lo;
  for (int a = 0; a < 3; ++a) {
    m_dims[a] = ext[a] > 0 ? std::max(2, static_cast<int>(std::ceil((resolution - 1) * ext[a] / longest - 1e-9)) + 1) : 2;
    m_h[a] = ext[a] > 0 ? ext[a] / (m_dims[a] - 1) : 0.0;
  }
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
  if (m_values.empty()) return 1.0;
  int i[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    double u = m_h[a] > 0 ? (p[a] - m_lo[a]) / m_h[a] : 0.0;
    if (!std::isfinite(u)) u = 0;
    u = std::clamp(u, 0.0, static_cast<double>(m_dims[a] - 1));
    i[a] = std::min(static_cast<int>(u), m_dims[a] - 2);
    f[a] = u - i[a];
  }
  double sum = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const int dx = corner & 1, dy = (corner >> 1) & 1, dz = corner >> 2;
    const double w = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
    sum += w * m_values[static_cast<std::size_t>(i[0] + dx) +
                        static_cast<std::size_t>(m_dims[0]) * (static_cast<std::size_t>(i[1] + dy) + static_cast<std::size_t>(m_dims[1]) * (i[2] + dz))];
  }
  return sum;
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
