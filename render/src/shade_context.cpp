// SPDX-License-Identifier: BSD-3-Clause
// render/src/shade_context.cpp -- per-tet normals and the light field for shaded frames
#include "shade_context.h"

#include <cmath>

#include "penumbra/core/thread_pool.h"

namespace penumbra::render::detail {

ShadeContext make_shade_context(const std::vector<WalkTet>& tets, const std::vector<Vec3d>& pts,
                                const std::int32_t* point_ids, const float* scalars, const Shading& shading) {
  ShadeContext sc;
  sc.point_ids = point_ids;
  sc.shading = shading;
  if (shading.model == LightingModel::light_volume && !shading.light_at) sc.light_rgb = shading.light_rgb->data();
  const double dl = length(shading.light_direction);
  sc.headlight = !(dl > 0);
  if (!sc.headlight) sc.to_light = shading.light_direction / dl;
  if (shading.shininess >= 0 && shading.shininess <= 1024 && shading.shininess == std::floor(shading.shininess))
    sc.whole_shininess = static_cast<int>(shading.shininess);
  if (shading.model == LightingModel::none) return sc;
  // The scalar is linear in a tet: its gradient is constant there, the sum over the faces'
  // area vectors weighted by the opposite value differences (divided by 6 x volume, which only
  // scales it: the direction is all Phong needs).
  sc.normals.resize(tets.size());
  parallel_for(tets.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const WalkTet& w = tets[i];
      const Vec3d p0 = pts[static_cast<std::size_t>(w.v[0])];
      const Vec3d e1 = pts[static_cast<std::size_t>(w.v[1])] - p0, e2 = pts[static_cast<std::size_t>(w.v[2])] - p0,
                  e3 = pts[static_cast<std::size_t>(w.v[3])] - p0;
      auto scalar = [&](int k) -> double { return scalars[point_ids[w.v[k]]]; };
      const double s0 = scalar(0);
      const Vec3d g =
          cross(e2, e3) * (scalar(1) - s0) + cross(e3, e1) * (scalar(2) - s0) + cross(e1, e2) * (scalar(3) - s0);
      const double gl = length(g);
      auto& n = sc.normals[i];
      if (std::isfinite(gl) && gl > 0) {
        n = {static_cast<float>(g.x / gl), static_cast<float>(g.y / gl), static_cast<float>(g.z / gl), 1.0f};
      } else {
        n = {0.0f, 0.0f, 0.0f, 0.0f};
      }
    }
  });
  return sc;
}

}  // namespace penumbra::render::detail
