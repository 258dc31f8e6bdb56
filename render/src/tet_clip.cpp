// SPDX-License-Identifier: BSD-3-Clause
// render/src/tet_clip.cpp -- a line clipped against one tet
#include "tet_clip.h"

#include <algorithm>
#include <cmath>

#include "walk_mesh.h"

namespace penumbra::render::detail {

ClipLine::ClipLine(const Vec3d& origin, const Vec3d& unit_dir) : o(origin), d(unit_dir) {
  const Vec3d helper = std::fabs(d.x) < 0.5 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
  u = normalize(cross(helper, d));
  v = cross(d, u);
}

bool clip_to_tet(const TetMesh& mesh, std::int32_t t, const ClipLine& r, double t_max, double& lo, double& hi) {
  const auto& tv = mesh.tets[static_cast<std::size_t>(t)];
  lo = 0.0;
  hi = t_max;
  for (const auto& f : kFaceVertices) {
    const Vec3d& a = mesh.points[static_cast<std::size_t>(tv[f[0]])];
    const Vec3d& b = mesh.points[static_cast<std::size_t>(tv[f[1]])];
    const Vec3d& c = mesh.points[static_cast<std::size_t>(tv[f[2]])];
    const Vec3d n = cross(b - a, c - a);  // outward
    const double h0 = dot(n, r.o - a), hd = dot(n, r.d);
    if (hd < 0) {
      lo = std::max(lo, -h0 / hd);
    } else if (hd > 0) {
      hi = std::min(hi, -h0 / hd);
    } else {
      const double nu = dot(n, r.u), nv = dot(n, r.v);
      const bool inside = h0 < 0 || (h0 == 0 && (nu < 0 || (nu == 0 && nv <= 0)));
      if (!inside) return false;
    }
    if (!(hi > lo)) return false;
  }
  return true;
}

Bvh tet_bvh(const TetMesh& mesh) {
  std::vector<Bounds> boxes(mesh.tets.size());
  for (std::size_t t = 0; t < boxes.size(); ++t)
    for (int k = 0; k < 4; ++k) boxes[t].extend(mesh.points[static_cast<std::size_t>(mesh.tets[t][k])]);
  return Bvh(boxes, 1e-9 * std::max(mesh.bounds.diagonal(), 1e-300), 4);
}

double scalar_in_tet(const TetMesh& mesh, const std::vector<float>& s, std::int32_t t, const Vec3d& x) {
  const auto& tv = mesh.tets[static_cast<std::size_t>(t)];
  Vec3d p[4];
  for (int k = 0; k < 4; ++k) p[k] = mesh.points[static_cast<std::size_t>(tv[k])];
  const double vol = signed_volume6(p[0], p[1], p[2], p[3]);
  double sum = 0;
  for (int k = 0; k < 4; ++k) {
    Vec3d q[4] = {p[0], p[1], p[2], p[3]};
    q[k] = x;
    sum += signed_volume6(q[0], q[1], q[2], q[3]) / vol * static_cast<double>(s[static_cast<std::size_t>(tv[k])]);
  }
  return sum;
}

}  // namespace penumbra::render::detail
