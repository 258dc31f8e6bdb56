// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/rays_enter_mesh.cpp -- whether a point's ray towards a light starts inside the mesh
#include <algorithm>
#include <cmath>
#include <string>

#include "penumbra/core/error.h"
#include "penumbra/render/light_volume.h"

namespace penumbra::render {
namespace {

// Whether unit direction d from corner c of tet `q` points into the tet: d is a combination of
// the three edges from c with no negative weight. The weights are the triple products of d with
// the edge pairs over that of the edges (Cramer's rule); a weight within rounding of zero (d in a
// face's plane) counts as entering.
bool points_into(const Vec3d q[4], int c, const Vec3d& d) {
  const Vec3d& o = q[c];
  const Vec3d e1 = q[(c + 1) % 4] - o, e2 = q[(c + 2) % 4] - o, e3 = q[(c + 3) % 4] - o;
  const double det = dot(e1, cross(e2, e3));
  const double w1 = dot(cross(e2, e3), d), w2 = dot(cross(e3, e1), d), w3 = dot(cross(e1, e2), d);
  const double sign = det < 0 ? -1.0 : 1.0;
  const double slack = 1e-12 * std::fabs(det) / std::max(length(e1) + length(e2) + length(e3), 1e-300);
  return sign * w1 >= -slack && sign * w2 >= -slack && sign * w3 >= -slack;
}

}  // namespace

std::vector<std::uint8_t> rays_enter_mesh(const TetMesh& mesh, const std::vector<std::int32_t>& points,
                                          const Light& light) {
  const std::int64_t np = static_cast<std::int64_t>(mesh.points.size());
  std::vector<std::int32_t> slot(mesh.points.size(), -1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    require(points[i] >= 0 && points[i] < np, "rays_enter_mesh: point " + std::to_string(points[i]) +
                                                  " is out of range; the mesh has " + std::to_string(np) + " points");
    slot[static_cast<std::size_t>(points[i])] = static_cast<std::int32_t>(i);
  }
  const Vec3d towards_directional = -normalize(light.vector);
  std::vector<std::uint8_t> enters(points.size(), 0);
  for (const auto& tet : mesh.tets) {
    Vec3d q[4];
    for (int c = 0; c < 4; ++c) q[c] = mesh.points[static_cast<std::size_t>(tet[c])];
    for (int c = 0; c < 4; ++c) {
      const std::int32_t s = slot[static_cast<std::size_t>(tet[c])];
      if (s < 0 || enters[static_cast<std::size_t>(s)]) continue;
      const Vec3d d = light.kind == Light::Kind::directional ? towards_directional : normalize(light.vector - q[c]);
      if (points_into(q, c, d)) enters[static_cast<std::size_t>(s)] = 1;
    }
  }
  return enters;
}

}  // namespace penumbra::render
