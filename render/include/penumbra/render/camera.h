// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/camera.h
#pragma once
#include "penumbra/core/vec3.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::render {

/// A ray origin + t * direction (direction need not be unit length unless stated).
struct Ray { Vec3d origin, direction; };

/// Perspective pinhole camera.
struct Camera {
  Vec3d eye{0, 0, 1};
  Vec3d target{0, 0, 0};
  Vec3d up{0, 1, 0};
  double fov_y_deg = 30.0;
  int width = 256;
  int height = 256;

  /// Camera at `eye` looking at `target`.
  static Camera look_at(Vec3d eye, Vec3d target, Vec3d up, double fov_y_deg, int width, int height);
  /// Cinema orbit: phi is the azimuth around +z from +x (degrees), theta the elevation from the
  /// xy-plane (degrees, -90..90). The eye sits on a sphere around the bounds' centre, far enough
  /// that the whole bounding sphere fits in the view.
  static Camera orbit(const Bounds& bounds, double phi_deg, double theta_deg, double fov_y_deg, int width, int height);
  /// The camera's orthonormal frame (right x up = -forward) and the half extents of its image
  /// plane one unit in front of the eye: pixel (px, py) looks along
  /// forward + right x + up y, x = (2 (px + 0.5) / width - 1) half_width, y likewise downwards.
  struct Frame {
    Vec3d forward, right, up;
    double half_width, half_height;
  };
  Frame frame() const;
  /// Unit-direction primary ray through the centre of pixel (px, py); py = 0 is the top row.
  Ray primary_ray(double px, double py) const;
  /// The same with the frame computed once (frame()): a renderer's per-pixel call then skips the
  /// frame's normalisations and tangent. Bit-identical to primary_ray(px, py).
  Ray primary_ray(const Frame& f, double px, double py) const;
};

}  // namespace penumbra::render

PNB_PUBLIC_END
