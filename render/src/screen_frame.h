// SPDX-License-Identifier: BSD-3-Clause
// render/src/screen_frame.h -- the per-frame screen-space data of ScreenGeometry (see
// walk_geometry.h): projected points and boundary faces binned by screen tile
#pragma once
#include <cstdint>
#include <vector>

#include "penumbra/core/vec3.h"
#include "penumbra/render/camera.h"
#include "walk_geometry.h"
#include "walk_mesh.h"

namespace penumbra::render::detail {

/// The screen frame of `camera` (same right and forward as Camera::primary_ray).
ScreenBasis screen_basis(const Camera& camera);

/// Screen coordinates and scalar of every point, point i's scalar being scalars[point_ids[i]];
/// empty when some point is not in front of the eye (by more than 1e-9 of the mesh size), in
/// which case the frame must project per ray.
std::vector<ScreenPoint> project_to_screen(const ScreenBasis& basis, const std::vector<Vec3d>& pts,
                                          const std::int32_t* point_ids, const float* scalars, const Bounds& bounds);

/// Boundary faces per screen tile of `tile` x `tile` pixels, row-major: those of tile i are
/// faces[start[i]] .. faces[start[i + 1] - 1], every face through which the ray of a pixel
/// centre of the tile may enter the mesh (a face turned away from the eye, or one whose box
/// holds none of the tile's pixel centres, is left out).
struct ScreenBins {
  std::vector<std::int32_t> start, faces;
};
ScreenBins bin_boundary_faces(const std::vector<BoundaryTriangle>& triangles, const std::vector<ScreenPoint>& screen,
                              const Camera& camera, int tile);

}  // namespace penumbra::render::detail
