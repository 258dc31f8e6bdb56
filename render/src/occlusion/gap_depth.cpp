// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/gap_depth.cpp -- exact optical depth over a shadow cone's initial gap
//
// The segment is clipped against every tet a BVH over the tets reports (the clip of the
// double-precision references, so a segment along a face is counted in exactly one tet); on each
// clipped piece the scalar is linear and the transfer function's pieces integrate tau exactly.
#include <cmath>
#include <string>

#include "bvh.h"
#include "lighting/extinction_table.h"
#include "tet_clip.h"
#include "penumbra/core/error.h"
#include "occlusion/occlusion_internals.h"

namespace penumbra::render {

struct GapDepth::Impl {
  std::shared_ptr<const TetMesh> mesh;
  detail::Bvh bvh;
  std::vector<float> scalars;
  lighting::ExtinctionTable table;
  bool bound = false;
};

GapDepth::GapDepth(std::shared_ptr<const TetMesh> mesh) : m_impl(std::make_unique<Impl>()) {
  require(mesh != nullptr, "GapDepth: mesh is null");
  // No tet (a rank's empty part): no gap ends here, and every depth asked of it is zero.
  m_impl->bvh = detail::tet_bvh(*mesh);
  m_impl->mesh = std::move(mesh);
}

GapDepth::~GapDepth() = default;
GapDepth::GapDepth(GapDepth&&) noexcept = default;
GapDepth& GapDepth::operator=(GapDepth&&) noexcept = default;

void GapDepth::set_field(const std::vector<float>& point_scalars, const TransferFunction& tf) {
  const TetMesh& mesh = *m_impl->mesh;
  require(point_scalars.size() == mesh.points.size(), "GapDepth: " + std::to_string(point_scalars.size()) +
                                                          " scalars for " + std::to_string(mesh.points.size()) +
                                                          " points; expected one per point");
  tf.validate();
  m_impl->scalars = point_scalars;
  m_impl->table = lighting::ExtinctionTable(tf);
  m_impl->bound = true;
}

double GapDepth::depth(const Vec3d& x, const Vec3d& direction, double length, double* covered) const {
  const double n = penumbra::length(direction);
  if (covered) *covered = 0;
  if (!m_impl->bound || !(length > 0) || !(n > 0) || !std::isfinite(n)) return 0.0;
  const TetMesh& mesh = *m_impl->mesh;
  const detail::ClipLine line(x, direction / n);
  double depth = 0;
  m_impl->bvh.for_each_on_line(line.o, line.d, 0.0, length, [&](std::int32_t t) {
    double lo, hi;
    if (!detail::clip_to_tet(mesh, t, line, length, lo, hi)) return;
    const double s0 = detail::scalar_in_tet(mesh, m_impl->scalars, t, line.o + line.d * lo);
    const double s1 = detail::scalar_in_tet(mesh, m_impl->scalars, t, line.o + line.d * hi);
    depth += m_impl->table.integral(s0, s1, hi - lo);
    if (covered) *covered += hi - lo;
  });
  return depth;
}

}  // namespace penumbra::render
