// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/view_cameras.h -- the config's cameras around a published mesh
#pragma once
#include <string>
#include <vector>

#include "config.h"
#include "penumbra/core/vec3.h"
#include "penumbra/render/camera.h"

namespace penumbra::insitu {

/// One camera of the run, with the database values of its images.
struct ViewCamera {
  render::Camera camera;
  std::string phi, theta, name;  ///< database values
  std::string stem;              ///< image file name stem without the cycle
};

/// The orbit cameras (every theta, then every phi, around `bounds`), then the look_at cameras,
/// whose phi and theta are those of their viewing direction as seen from the target, so that
/// their rows sort beside the orbit's in Cinema viewers.
std::vector<ViewCamera> view_cameras(const Config& config, const Bounds& bounds);

}  // namespace penumbra::insitu
