// SPDX-License-Identifier: BSD-3-Clause
// render/src/shading.cpp -- checks of the shading options
#include "penumbra/render/shading.h"

#include <cmath>
#include <string>

#include "penumbra/core/error.h"

namespace penumbra::render {

void Shading::validate(const char* call, std::size_t point_count) const {
  const std::string where = std::string(call) + ": shading";
  for (const auto& [name, value] : {std::pair{"ambient", ambient}, std::pair{"diffuse", diffuse},
                                    std::pair{"specular", specular}, std::pair{"shininess", shininess}})
    require(std::isfinite(value) && value >= 0,
            where + "." + name + " = " + std::to_string(value) + "; expected a finite value >= 0");
  const Vec3d& d = light_direction;
  require(std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z),
          where + ".light_direction is not finite; expected a direction or the zero vector (headlight)");
  if (model != LightingModel::light_volume) return;
  if (light_at) return;
  require(light_rgb != nullptr, where + ": model light_volume needs light_rgb (3 values per point) or light_at");
  require(light_rgb->size() == 3 * point_count,
          where + ".light_rgb has " + std::to_string(light_rgb->size()) + " values but the mesh has " +
              std::to_string(point_count) + " points; expected 3 per point");
}

}  // namespace penumbra::render
