// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/transmittance_reference.cpp -- double-precision transmittance to a light
//
// Independent of the solver: no adjacency walk, no level-0 grid and no ExtinctionTable. The ray
// from x to the light is clipped against every tet a BVH over all tets reports; a ray lying in a
// face plane is displaced by (eps u + eps^2 v) (u, v perpendicular to the ray), so of the tets
// sharing that face or edge exactly one contains it. Each clipped interval is cut where the
// scalar crosses a transfer-function breakpoint; on each piece tau is linear in the distance and
// its integral is tau(midpoint) * length, exactly.
#include <algorithm>
#include <cmath>
#include <limits>

#include "bvh.h"
#include "tet_clip.h"
#include "penumbra/core/error.h"
#include "penumbra/render/light_volume.h"

namespace penumbra::render {
namespace {

// A line towards a light; t_max ends it at a point light.
struct Line : detail::ClipLine {
  using detail::ClipLine::ClipLine;
  double t_max = 0;
};

bool clip(const TetMesh& mesh, std::int32_t t, const Line& r, double& lo, double& hi) {
  return detail::clip_to_tet(mesh, t, r, r.t_max, lo, hi);
}

double interval_depth(const TransferFunction& tf, const std::vector<double>& breaks, double s0, double s1, double len) {
  if (std::isnan(s0) || std::isnan(s1) || !(len > 0)) return 0.0;
  std::vector<double> cuts{0.0, 1.0};
  for (double x : breaks)
    if ((x > s0 && x < s1) || (x < s0 && x > s1)) cuts.push_back((x - s0) / (s1 - s0));
  std::sort(cuts.begin(), cuts.end());
  double depth = 0;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double fm = 0.5 * (cuts[i] + cuts[i + 1]);
    depth += tf.extinction(s0 + (s1 - s0) * fm) * (cuts[i + 1] - cuts[i]) * len;
  }
  return depth;
}

Line line_to(const Light& light, const Vec3d& x) {
  Vec3d d{1, 0, 0};
  double t_max = std::numeric_limits<double>::infinity();
  if (light.kind == Light::Kind::directional) {
    d = -normalize(light.vector);
  } else {
    const Vec3d to = light.vector - x;
    t_max = length(to);
    if (t_max > 0) d = to / t_max;
  }
  Line r(x, d);
  r.t_max = t_max;
  return r;
}

bool ray_meets_box(const Line& r, const Bounds& box) {
  double t0 = 0.0, t1 = r.t_max;
  for (int a = 0; a < 3; ++a) {
    if (r.d[a] == 0.0) {
      if (r.o[a] < box.lo[a] || r.o[a] > box.hi[a]) return false;
      continue;
    }
    double ta = (box.lo[a] - r.o[a]) / r.d[a], tb = (box.hi[a] - r.o[a]) / r.d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace

struct LightTransmittanceReference::Impl {
  std::shared_ptr<const TetMesh> mesh;
  detail::Bvh bvh;
};

LightTransmittanceReference::LightTransmittanceReference(std::shared_ptr<const TetMesh> mesh)
    : m_impl(std::make_unique<Impl>()) {
  require(mesh != nullptr, "LightTransmittanceReference: mesh is null");
  m_impl->bvh = detail::tet_bvh(*mesh);
  m_impl->mesh = std::move(mesh);
}

LightTransmittanceReference::~LightTransmittanceReference() = default;

double LightTransmittanceReference::optical_depth(const std::vector<float>& scalars, const TransferFunction& tf,
                                                  const Light& light, const Vec3d& x) const {
  const TetMesh& mesh = *m_impl->mesh;
  require(scalars.size() == mesh.points.size(), "LightTransmittanceReference: expected one scalar per point");
  const Line r = line_to(light, x);
  if (!(r.t_max > 0)) return 0.0;
  const std::vector<double> breaks = tf.breakpoints();
  double depth = 0;
  m_impl->bvh.for_each_on_line(r.o, r.d, 0.0, r.t_max, [&](std::int32_t t) {
    double lo, hi;
    if (!clip(mesh, t, r, lo, hi)) return;
    const double s0 = detail::scalar_in_tet(mesh, scalars, t, r.o + r.d * lo);
    const double s1 = detail::scalar_in_tet(mesh, scalars, t, r.o + r.d * hi);
    depth += interval_depth(tf, breaks, s0, s1, hi - lo);
  });
  return depth;
}

double LightTransmittanceReference::transmittance(const std::vector<float>& scalars, const TransferFunction& tf,
                                                  double sigma_a, const Light& light, const Vec3d& x,
                                                  const std::vector<Bounds>& occluders) const {
  const Line r = line_to(light, x);
  for (const Bounds& box : occluders)
    if (ray_meets_box(r, box)) return 0.0;
  return std::exp(-sigma_a * optical_depth(scalars, tf, light, x));
}

}  // namespace penumbra::render
