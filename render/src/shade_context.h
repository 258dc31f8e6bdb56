// SPDX-License-Identifier: BSD-3-Clause
// render/src/shade_context.h -- per-frame shading state of the CPU walk (see
// penumbra/render/shading.h)
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "penumbra/core/vec3.h"
#include "penumbra/render/shading.h"
#include "walk_mesh.h"

namespace penumbra::render::detail {

// What a shaded render needs per frame: unit scalar gradients per walk tet (w = 1 where the
// gradient exists, 0 where it vanishes or a vertex has no data) and the light field.
struct ShadeContext {
  std::vector<std::array<float, 4>> normals;
  const float* light_rgb = nullptr;  // 3 per point, original point ids; null: L = 1
  const std::int32_t* point_ids = nullptr;  // the mesh's id of each walk point id
  Shading shading;
  bool headlight = true;
  Vec3d to_light{0, 0, 0};
  /// shading.shininess when it is a whole number up to 1024 (then the highlight takes a few
  /// multiplications instead of std::pow, which cost about a third of a lit walk), else -1.
  int whole_shininess = -1;

  // The Phong factor of a tet seen along unit direction d. A vanishing gradient (a constant
  // field) has no orientation: it is lit as if facing the light, without a highlight.
  double phong(std::int32_t tet, const Vec3d& d) const {
    if (shading.model == LightingModel::none) return 1.0;
    const auto& n = normals[static_cast<std::size_t>(tet)];
    if (n[3] == 0.0f) return shading.ambient + shading.diffuse;
    const Vec3d normal{n[0], n[1], n[2]}, view = -d;
    const Vec3d l = headlight ? view : to_light;
    // The half vector; a headlight's is the view direction itself.
    Vec3d h = view;
    if (!headlight) {
      h = l + view;
      const double hl = length(h);
      h = hl > 0 ? h / hl : l;
    }
    // Two-sided: an iso-surface is lit from either side.
    const double lit = shading.ambient + shading.diffuse * std::fabs(dot(normal, l));
    if (shading.specular == 0.0) return lit;
    return lit + shading.specular * highlight(std::fabs(dot(normal, h)));
  }

  /// c^shininess for c in [0, 1].
  double highlight(double c) const {
    if (whole_shininess < 0) return std::pow(c, shading.shininess);
    double result = 1.0;
    for (int e = whole_shininess; e != 0; e >>= 1, c *= c)
      if (e & 1) result *= c;
    return result;
  }

  /// L at point x of a face with vertices `ids` and interpolation weights `mu`: evaluated at x in
  /// image space (Shading::light_at), else interpolated from the vertices' light.
  void face_light(const std::int32_t ids[3], const double mu[3], const Vec3d& x, double out[3]) const {
    if (shading.light_at) {
      shading.light_at(x, out);
      for (int c = 0; c < 3; ++c)
        if (!std::isfinite(out[c])) out[c] = 0.0;
      return;
    }
    double l[3][3];
    for (int j = 0; j < 3; ++j) light_at(ids[j], l[j]);
    for (int c = 0; c < 3; ++c) out[c] = mu[0] * l[0][c] + mu[1] * l[1][c] + mu[2] * l[2][c];
  }

  void light_at(std::int32_t point, double out[3]) const {
    for (int c = 0; c < 3; ++c) {
      const float v = light_rgb ? light_rgb[3 * static_cast<std::size_t>(point_ids[point]) + c] : 1.0f;
      out[c] = std::isfinite(v) ? v : 0.0;
    }
  }
};

/// The shading state for `shading` (validated) over the walk tets `tets` of points `pts`; walk
/// point i is the mesh's point point_ids[i], whose scalar is scalars[point_ids[i]].
ShadeContext make_shade_context(const std::vector<WalkTet>& tets, const std::vector<Vec3d>& pts,
                                const std::int32_t* point_ids, const float* scalars, const Shading& shading);

}  // namespace penumbra::render::detail
