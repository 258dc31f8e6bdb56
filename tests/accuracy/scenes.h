// SPDX-License-Identifier: BSD-3-Clause
// tests/accuracy/scenes.h -- shared set-up for the ray-caster accuracy tests
#pragma once
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "fixtures/meshes.h"
#include "penumbra/render/cpu_ray_caster.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::test {

inline std::shared_ptr<const render::TetMesh> prepare(const fixtures::OwnedMesh& m) {
  return std::make_shared<const render::TetMesh>(render::prepare_tet_mesh(m.view()));
}

/// Homogeneous medium: extinction sigma and white colour whatever the scalar.
inline render::TransferFunction constant_tf(double sigma) {
  render::TransferFunction tf;
  tf.colors = {{0.0, 1.0, 1.0, 1.0}};
  tf.opacities = {{0.0, sigma}};
  return tf;
}

/// Length of the line origin + t dir (t >= 0, unit dir) inside the box [lo, hi].
inline double chord(const Vec3d& lo, const Vec3d& hi, const Vec3d& o, const Vec3d& d) {
  double t0 = 0, t1 = 1e300;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) {
      if (o[a] < lo[a] || o[a] > hi[a]) return 0;
      continue;
    }
    double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t1 > t0 ? t1 - t0 : 0.0;
}

inline std::vector<float> to_float(const std::vector<double>& v) { return {v.begin(), v.end()}; }

}  // namespace penumbra::test
