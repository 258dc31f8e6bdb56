// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/view_cameras.cpp
#include "view_cameras.h"

#include <algorithm>
#include <cmath>

#include "context.h"

namespace penumbra::insitu {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Degrees to two decimals, as the database shows them.
std::string degrees(double radians) { return format_number(std::round(radians * 180 / kPi * 100) / 100); }

}  // namespace

std::vector<ViewCamera> view_cameras(const Config& config, const Bounds& bounds) {
  std::vector<ViewCamera> cameras;
  if (config.orbit)
    for (double theta : config.orbit->theta)
      for (double phi : config.orbit->phi) {
        ViewCamera e{render::Camera::orbit(bounds, phi, theta, config.orbit->fov_y_deg, config.width, config.height),
                     format_number(phi), format_number(theta), "orbit", ""};
        e.stem = "phi" + e.phi + "_theta" + e.theta;
        cameras.push_back(std::move(e));
      }
  for (const auto& c : config.look_at) {
    const Vec3d d = normalize(c.eye - c.target);
    cameras.push_back({render::Camera::look_at(c.eye, c.target, c.up, c.fov_y_deg, config.width, config.height),
                       degrees(std::atan2(d.y, d.x)), degrees(std::asin(std::clamp(d.z, -1.0, 1.0))), c.name, c.name});
  }
  return cameras;
}

}  // namespace penumbra::insitu
