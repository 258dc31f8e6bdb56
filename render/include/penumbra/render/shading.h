// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/shading.h -- how samples are lit: emission only, gradient
// Phong, or Phong times a light volume L(x) (Shih, Zhang & Ma, eq. 3)
#pragma once
#include <functional>
#include <vector>

#include "penumbra/core/vec3.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::render {

enum class LightingModel {
  none,          ///< emission-absorption: the transfer function's colour as is
  phong,         ///< colour x (ambient + diffuse + specular) from the scalar gradient
  light_volume,  ///< colour x L(x) x (ambient + diffuse + specular); L per point (light_rgb)
};

/// Shading of the emitted colour. The scalar is linear in a tet, so its gradient (the normal) and
/// the Phong factor are constant along each tet segment; L(x) is interpolated linearly from the
/// points like the scalar. The emission c(s) L(x) is then the product of two linear functions;
/// a segment integrates it as the linear function through its end values, which is exact when
/// either factor is constant and otherwise differs by O(segment length^2) of the change in L.
struct Shading {
  LightingModel model = LightingModel::none;
  /// Light colour field L, 3 floats (r, g, b) per mesh point; for light_volume (this or
  /// light_at) and ignored otherwise. Non-finite values count as no light (0).
  const std::vector<float>* light_rgb = nullptr;
  /// Image-space light: L at any point x, written to rgb; when set it replaces light_rgb and is
  /// evaluated at every segment end of every ray (CPU ray caster only). Called concurrently.
  std::function<void(const Vec3d& x, double rgb[3])> light_at;
  /// Unit direction towards the key light for the diffuse and specular terms, in world space;
  /// the zero vector means a headlight (towards the eye, per ray).
  Vec3d light_direction{0, 0, 0};
  double ambient = 0.35;
  double diffuse = 0.55;
  double specular = 0.25;
  double shininess = 24.0;

  /// Throws Error(invalid_argument) naming `call` for a light field of the wrong size, a missing
  /// one, negative coefficients or a direction that is neither zero nor finite.
  void validate(const char* call, std::size_t point_count) const;
};

}  // namespace penumbra::render

PNB_PUBLIC_END
