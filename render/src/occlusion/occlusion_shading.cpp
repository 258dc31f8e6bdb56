// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/occlusion_shading.cpp -- cones towards the eye and towards lights
#include <algorithm>
#include <cmath>

#include "occlusion/occlusion_internals.h"

namespace penumbra::render {

double directional_occlusion(const ConeTracer& tracer, const Vec3d& x, const Vec3d& eye) {
  // Cones point at the viewer (thesis sec. 3.3.1): what is in front of the sample darkens it.
  return tracer.transmittance(x, eye - x);
}

double shadow_transmittance(const ConeTracer& tracer, const ShadowLight& light, const Vec3d& x) {
  constexpr double kPi = 3.14159265358979323846;
  if (light.kind == ShadowLight::Kind::directional) return tracer.transmittance(x, -light.vector);
  const Vec3d to_light = light.vector - x;
  const double dist = length(to_light);
  if (!(dist > 0)) return 1.0;
  if (light.kind == ShadowLight::Kind::spot) {
    const double sl = length(light.spot_direction);
    if (!(sl > 0)) return 0.0;
    const double c = dot(-to_light, light.spot_direction) / (dist * sl);
    if (c < std::cos(light.spot_angle_deg * kPi / 180.0)) return 0.0;
  }
  // Nothing beyond the light occludes it: the cone stops there.
  return tracer.transmittance(x, to_light, dist);
}

double gap_transmittance(const ConeTracer& tracer, const ShadowLight& light, const Vec3d& x, const GapDepth& gap) {
  if (light.kind == ShadowLight::Kind::directional) return std::exp(-gap.depth(x, -light.vector, tracer.gap()));
  const Vec3d to_light = light.vector - x;
  return std::exp(-gap.depth(x, to_light, std::min(tracer.gap(), length(to_light))));
}

double shadow_transmittance(const ConeTracer& tracer, const ShadowLight& light, const Vec3d& x, const GapDepth& gap) {
  const double cone = shadow_transmittance(tracer, light, x);
  return cone > 0 ? cone * gap_transmittance(tracer, light, x, gap) : cone;
}

}  // namespace penumbra::render
