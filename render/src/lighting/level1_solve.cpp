// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level1_solve.cpp -- the departure value of level 1 and first pass timings
#include "level1_solve.h"

#include <algorithm>
#include <cmath>

#include "penumbra/core/elapsed.h"
#include "penumbra/core/thread_pool.h"
#include "shader_constants.h"
#include "tet_geometry.h"

namespace penumbra::render::lighting {
namespace {

// interpolate_light: optical depth interpolated up to this change across the light within a tet
// (a factor 4 in rho), rho interpolated linearly from the next (a factor 16); shared with
// light_level1.comp.
using shader::kGeometricDepth;
using shader::kLinearDepth;

}  // namespace

double box_path_length(const Bounds& box, const Vec3d& x, const Light& light) {
  Vec3d d;
  double t1;
  if (light.kind == Light::Kind::directional) {
    d = -normalize(light.vector);
    t1 = HUGE_VAL;
  } else {
    const Vec3d r = light.vector - x;
    t1 = length(r);
    if (!(t1 > 0)) return 0.0;
    d = r / t1;
  }
  double t0 = 0.0;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (x[a] < box.lo[a] || x[a] > box.hi[a]) return 0.0;
      continue;
    }
    double ta = (box.lo[a] - x[a]) / d[a], tb = (box.hi[a] - x[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t1 > t0 ? t1 - t0 : 0.0;
}

double transverse_change(const Vec3d p[4], const double value[4], const Vec3d& u) {
  const Vec3d g = linear_gradient(p, value);
  const Vec3d across = g - u * dot(g, u);
  double size = 0.0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) size = std::max(size, dot(p[b] - p[a], p[b] - p[a]));
  return length(across) * std::sqrt(size);
}

double interpolate_light(const std::array<double, 4>& w, const double rho[4], const double path[4], double path_d,
                         const Vec3d corner[4], const Vec3d& u) {
  double lo = HUGE_VAL, linear = 0.0;
  for (int k = 0; k < 4; ++k) {
    lo = std::min(lo, rho[k]);
    linear += w[k] * rho[k];
  }
  if (!(lo > 0.0)) return linear;  // an exactly dark corner (occluder, flushed): a shadow edge
  // Mean extinction along the rays: interpolated optical depth over interpolated path length.
  double depth[4], depth_mean = 0.0, path_mean = 0.0;
  for (int k = 0; k < 4; ++k) {
    depth[k] = -std::log(rho[k]);
    depth_mean += w[k] * depth[k];
    path_mean += w[k] * path[k];
  }
  if (!(path_mean > 0.0)) return path_d > 0.0 ? std::nan("") : linear;  // the caller walks on
  const double m = depth_mean / path_mean;
  double residual[4];
  for (int k = 0; k < 4; ++k) residual[k] = depth[k] - m * path[k];
  const double across = transverse_change(corner, residual, u);
  const double beta = std::clamp((across - kGeometricDepth) / (kLinearDepth - kGeometricDepth), 0.0, 1.0);
  const double geometric = std::exp(-m * path_d);
  return (1.0 - beta) * geometric + beta * linear;
}

void prime_pass_timing(const Level1Context& ctx, PassState& state) {
  using Clock = std::chrono::steady_clock;
  const std::size_t np = ctx.mesh.points.size();
  const std::size_t count = std::min(np, kLevel1Batch);
  if (count == 0) return;
  const Vec3d towards{0, 0, 1};
  std::vector<ParallelPoint> projected;
  const std::vector<float> zero(np, 0.0f);
  project_parallel(ctx.mesh, towards, zero, projected);  // the first touch of `projected`, untimed
  auto t0 = Clock::now();
  project_parallel(ctx.mesh, towards, zero, projected);
  std::vector<float> xy;
  hint_plane(projected, xy);
  state.full_setup_ms = 1.5 * ms_since(t0);
  std::vector<std::int32_t> starts(np, -1);
  t0 = Clock::now();
  hint_parallel_starts(ctx.topology.walk_tets, xy, 0, std::min(kHintSlice, ctx.topology.walk_tets.size()), starts);
  state.hint_slice_ms = 1.5 * ms_since(t0);
  const ExtinctionTable unit(TransferFunction{{{0.0, 1.0, 1.0, 1.0}}, {{0.0, 1.0}}});
  const WalkInput in{ctx.topology.walk_tets, ctx.topology.tet_offsets, ctx.topology.star, unit, projected.data(),
                     ctx.mesh.points.data(), nullptr};
  std::vector<std::vector<WalkCrossing>> records(count);
  std::vector<WalkJob> jobs(count);
  for (std::size_t i = 0; i < count; ++i) {
    const auto v = static_cast<std::int32_t>(i * np / count);
    jobs[i] = {v, ctx.mesh.points[static_cast<std::size_t>(v)], towards, ctx.step_of(static_cast<std::size_t>(v)),
               &starts[static_cast<std::size_t>(v)], &records[i], {}};
  }
  t0 = Clock::now();
  parallel_for(count, 64, [&](std::size_t b, std::size_t e) { walk_batch(in, jobs.data() + b, e - b); });
  state.vertex_ms = 1.5 * ms_since(t0) / static_cast<double>(count);
}

}  // namespace penumbra::render::lighting
