// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/local_frame.h -- the frame float32 data of a mesh are written in
#pragma once
#include <cmath>

#include "penumbra/core/vec3.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra {

/// A mesh's local frame: world point p is (p - center) / scale there. Float32 copies of a mesh
/// (the GPU's points, grids, camera and lights) are written in it, so that they keep the mesh's
/// own relative precision wherever it sits and whatever its size: products of coordinates and
/// lengths neither overflow nor underflow float32. The scale is a power of two, so that lengths,
/// extinctions (per unit length) and areas convert without rounding. Conversions run in double.
///
/// of(bounds) takes the centre and the diagonal of the bounds given: a rank of a partitioned mesh
/// passes the global bounds, so that every rank writes the same frame.
struct LocalFrame {
  Vec3d center{0, 0, 0};
  double scale = 1;  ///< a power of two: world length of one local unit

  bool operator==(const LocalFrame&) const = default;

  /// The frame around `bounds`: its centre, and the smallest power of two at least its diagonal
  /// (1 for empty or single-point bounds), so local coordinates lie within [-0.5, 0.5].
  static LocalFrame of(const Bounds& bounds) {
    LocalFrame f;
    if (bounds.empty()) return f;
    f.center = bounds.center();
    const double d = bounds.diagonal();
    if (d > 0 && std::isfinite(d)) {
      int e = 0;
      const double m = std::frexp(d, &e);  // d = m 2^e, m in [0.5, 1)
      f.scale = std::ldexp(1.0, m == 0.5 ? e - 1 : e);
    }
    return f;
  }

  Vec3d point(const Vec3d& world) const { return (world - center) / scale; }
  double length(double world) const { return world / scale; }
  /// Extinction (per unit length) in the frame: the optical depth of a segment is unchanged.
  double extinction(double per_world_unit) const { return per_world_unit * scale; }
};

}  // namespace penumbra

PNB_PUBLIC_END
