// render/src/lighting/level1_solve.cpp -- the tet walk and the ordered semi-Lagrangian passes
#include "level1_solve.h"

#include <algorithm>
#include <cmath>

#include "penumbra/core/morton.h"
#include "penumbra/core/thread_pool.h"
#include "tet_geometry.h"

namespace penumbra::render::lighting {
namespace {

// interpolate_light: optical depth interpolated up to this change across the light within a tet
// (a factor 4 in rho), rho interpolated linearly from the next (a factor 16).
constexpr double kGeometricDepth = 1.3862943611198906;
constexpr double kLinearDepth = 2.772588722239781;
// Vertices per batch of a pass: the granularity at which a time budget can stop it.
constexpr std::size_t kBatch = 2048;

// Optical depth over [ta, tb] of the ray x + t d in the tet whose field slot is `slot`.
double segment_depth(const Level1Context& ctx, std::int32_t slot, const Vec3d& x, const Vec3d& d, double ta,
                     double tb, int& piece_hint) {
  if (!(tb > ta)) return 0.0;
  const LinearScalar& f = ctx.field.linear[static_cast<std::size_t>(slot)];
  if (std::isnan(f.offset)) return 0.0;
  // The scalar along the segment: s(x + t d) = s(x) + t (grad . d) within the tet.
  const double s_x = f.at(x);
  const double slope = dot(f.grad, d);
  return ctx.field.table.integral(s_x + slope * ta, s_x + slope * tb, tb - ta, &piece_hint);
}

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

VertexOrder order_vertices(const TetMesh& mesh, const Level1Topology& topology, const Light& light, double step) {
  // This runs as one piece of a frame budget, so every stage is parallel: keys, the sort (two
  // halves, then a merge), the Morton codes and the sorts within groups.
  const std::size_t np = mesh.points.size();
  const Vec3d u = light.kind == Light::Kind::directional ? normalize(light.vector) : Vec3d{};
  std::vector<double> key(np);
  parallel_for(np, 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p)
      key[p] = light.kind == Light::Kind::directional ? dot(mesh.points[p], u) : length(mesh.points[p] - light.vector);
  });
  std::vector<std::pair<double, std::int32_t>> keyed;
  keyed.reserve(np);
  for (std::size_t p = 0; p < np; ++p)
    if (topology.tet_offsets[p] != topology.tet_offsets[p + 1]) keyed.emplace_back(key[p], static_cast<std::int32_t>(p));
  // (key, id) pairs are all distinct, so the halves sorted apart and merged give std::sort's order.
  const auto middle = keyed.begin() + static_cast<std::ptrdiff_t>(keyed.size() / 2);
  parallel_for(2, 1, [&](std::size_t h, std::size_t) {
    if (h == 0)
      std::sort(keyed.begin(), middle);
    else
      std::sort(middle, keyed.end());
  });
  std::inplace_merge(keyed.begin(), middle, keyed.end());
  VertexOrder order;
  order.vertices.reserve(keyed.size());
  double group_start = -HUGE_VAL;
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    if (keyed[i].first >= group_start + 0.5 * step) {
      if (i > 0) order.group_end.push_back(i);
      group_start = keyed[i].first;
    }
    order.vertices.push_back(keyed[i].second);
  }
  if (!keyed.empty()) order.group_end.push_back(keyed.size());
  // Within a group any order is valid; a Morton (Z-order) curve of 20 bits per axis keeps the
  // walks of consecutive vertices in the same part of the mesh, and so of memory (sorted by key
  // they would jump across the whole slab).
  const Vec3d lo = mesh.bounds.lo, ext = mesh.bounds.hi - mesh.bounds.lo;
  std::vector<std::uint64_t> codes(np, 0);
  parallel_for(np, 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p) {
      std::uint64_t code = 0;
      for (int a = 0; a < 3; ++a) {
        const double f = std::clamp(ext[a] > 0 ? (mesh.points[p][a] - lo[a]) / ext[a] : 0.0, 0.0, 1.0);
        code |= spread_bits_3d(static_cast<std::uint32_t>(f * 1048575.0)) << (2 - a);  // x most significant
      }
      codes[p] = code;
    }
  });
  const std::size_t groups = order.group_end.size();
  order.group_of.assign(np, -1);
  parallel_for(groups, 64, [&](std::size_t gb, std::size_t ge) {
    for (std::size_t g = gb; g < ge; ++g) {
      const std::size_t begin = g == 0 ? 0 : order.group_end[g - 1], end = order.group_end[g];
      std::sort(order.vertices.begin() + static_cast<std::ptrdiff_t>(begin),
                order.vertices.begin() + static_cast<std::ptrdiff_t>(end), [&](std::int32_t a, std::int32_t b) {
                  return codes[static_cast<std::size_t>(a)] < codes[static_cast<std::size_t>(b)];
                });
      for (std::size_t i = begin; i < end; ++i)
        order.group_of[static_cast<std::size_t>(order.vertices[i])] = static_cast<std::int32_t>(g);
    }
  });
  order.path_length.assign(np, 0.0);
  parallel_for(np, 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p) order.path_length[p] = box_path_length(mesh.bounds, mesh.points[p], light);
  });
  return order;
}

bool level1_pass(const Level1Context& ctx, const Light& light, const std::vector<float>& rho0,
                 const VertexOrder& order, std::vector<float>& rho1, PassState& state, std::atomic<std::size_t>& lost,
                 std::chrono::steady_clock::time_point deadline) {
  const TetMesh& mesh = ctx.mesh;
  const bool point = light.kind == Light::Kind::point;
  const Vec3d back = point ? Vec3d{} : -normalize(light.vector);
  const std::size_t np = rho1.size();
  if (state.start_tet.size() != np) state.start_tet.assign(np, -1);
  if (!ctx.record_walks)
    state.walks = {};
  else if (state.walks.size() != np)
    state.walks.assign(np, RecordedWalk{});
  if (!state.in_pass) {
    state.full = state.departure_tet.size() != np;
    if (state.full) {
      state.departure_tet.assign(np, -1);
      state.stale.assign(np, 1);
    }
    state.next.resize(np);
    state.changed.assign(np, 0);
    state.residual = 0.0;
    state.next_group = 0;
    state.next_vertex = 0;
    state.in_pass = true;
    // A directional light's rays are all parallel: every point projected once per pass start
    // (the field's scalars ride along), so a walk step reads one 32-byte record per point.
    if (!point && state.full) project_parallel(mesh, back, ctx.field.scalars, state.parallel);
  }
  const bool full = state.full;
  const auto& topo = ctx.topology;
  const WalkInput walk_input{topo.walk_tets, topo.tet_offsets, topo.star, ctx.field.table,
                             point ? nullptr : state.parallel.data(), mesh.points.data(), ctx.field.scalars.data()};

  auto departure_value = [&](const Trace& tr, const Vec3d& end, RecordedWalk& walk) {
    if (!walk.has_path) {
      walk.path = box_path_length(mesh.bounds, end, light);
      walk.has_path = true;
    }
    const std::array<double, 4> w{walk.weights[0], walk.weights[1], walk.weights[2], walk.weights[3]};
    const auto& tv = topo.walk_tets[static_cast<std::size_t>(tr.tet)].v;
    double values[4], path[4];
    Vec3d corner[4];
    for (int k = 0; k < 4; ++k) {
      const auto c = static_cast<std::size_t>(tv[k]);
      values[k] = rho1[c];
      corner[k] = mesh.points[c];
      path[k] = order.path_length[c];
    }
    const Vec3d u = point ? normalize(end - light.vector) : -back;
    return interpolate_light(w, values, path, walk.path, corner, u);
  };

  auto update = [&](std::int32_t v) -> float {
    const Vec3d& x = mesh.points[static_cast<std::size_t>(v)];
    for (const Bounds& box : ctx.occluders)
      if (inside_box(x, box)) return 0.0f;
    Vec3d d = back;
    double len = ctx.step_of(static_cast<std::size_t>(v));
    bool reaches_light = false;
    if (point) {
      const Vec3d r = light.vector - x;
      const double dist = length(r);
      if (dist == 0.0) return 1.0f;
      d = r / dist;
      // Near the light rho has a cone tip no interpolation follows: walk the rest of the way.
      if (dist <= 2.0 * len) {
        len = dist;
        reaches_light = true;
      }
    }
    const auto vv = static_cast<std::size_t>(v);
    thread_local RecordedWalk unrecorded;  // walks are not kept: this one lives for one vertex
    RecordedWalk& walk = state.walks.empty() ? unrecorded : state.walks[vv];
    if (state.walks.empty()) walk.valid = false;
    Trace tr;
    if (walk.valid) {
      // The same walk as last time: only the extinction along it is new.
      int piece_hint = -1;
      for (const WalkSegment& seg : walk.segments)
        tr.depth += segment_depth(ctx, seg.slot, x, d, seg.ta, seg.tb, piece_hint);
      tr.kind = static_cast<Trace::Kind>(walk.kind);
      tr.tet = walk.tet;
      tr.end = tr.kind == Trace::Kind::inside ? len : static_cast<double>(walk.end);
    } else {
      // Walked into a scratch list and copied once: growing each vertex's own list step by step
      // cost several allocations per vertex, a large share of a first pass.
      thread_local std::vector<WalkSegment> walked;
      walked.clear();
      tr = walk_to_light(walk_input, v, x, d, len, &state.start_tet[vv], &walked);
      walk.segments.assign(walked.begin(), walked.end());
      walk.tet = tr.tet;
      walk.kind = static_cast<std::uint8_t>(tr.kind);
      walk.end = static_cast<float>(tr.end);
      for (int k = 0; k < 4; ++k) walk.weights[k] = tr.weights[k];
      walk.has_path = false;
      walk.valid = tr.kind != Trace::Kind::lost;
      if (!walk.valid) walk.segments = {};
    }
    Vec3d end = x + d * tr.end;
    double upstream = 0.0;
    state.departure_tet[vv] = -1;
    state.stale[vv] = 0;
    if (tr.kind == Trace::Kind::inside && !reaches_light) {
      state.departure_tet[vv] = tr.tet;
      // A corner not in an earlier group was read before its update in this pass.
      for (std::int32_t c : topo.walk_tets[static_cast<std::size_t>(tr.tet)].v)
        if (order.group_of[static_cast<std::size_t>(c)] >= order.group_of[vv]) state.stale[vv] = 1;
      upstream = departure_value(tr, end, walk);
      // A departure tet with every corner on the inflow boundary carries no extinction to
      // interpolate from: walk on to where the ray leaves the mesh bounds instead (not recorded:
      // rare, and it depends on the values).
      if (std::isnan(upstream)) {
        walk.valid = false;
        tr = walk_to_light(walk_input, v, x, d, box_path_length(mesh.bounds, x, light) * (1 + 1e-9) + 1e-300);
        end = x + d * tr.end;
        state.departure_tet[vv] = -1;
        state.stale[vv] = 0;
      }
    }
    switch (tr.kind) {
      case Trace::Kind::inside:
        if (reaches_light || std::isnan(upstream)) upstream = 1.0;
        break;
      case Trace::Kind::left_mesh:
        upstream = ctx.grid.sample_prefer_outside(rho0, end);
        break;
      default:
        lost.fetch_add(1, std::memory_order_relaxed);
        upstream = ctx.grid.sample(rho0, end);
        break;
    }
    for (const Bounds& box : ctx.occluders)
      if (segment_meets_box(x, end, box)) return 0.0f;
    return static_cast<float>(flush(upstream * std::exp(-ctx.sigma_a * tr.depth)));
  };

  double residual = state.residual;
  auto run = [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const std::int32_t v = order.vertices[i];
      const auto vv = static_cast<std::size_t>(v);
      // After the first pass a vertex whose inputs are unchanged keeps its value: only stale
      // reads and the vertices downstream of a change are recomputed.
      bool recompute = full || state.stale[vv];
      if (!recompute && state.departure_tet[vv] >= 0)
        for (std::int32_t c : topo.walk_tets[static_cast<std::size_t>(state.departure_tet[vv])].v)
          recompute = recompute || state.changed[static_cast<std::size_t>(c)];
      state.next[vv] = recompute ? update(v) : rho1[vv];
    }
  };
  // Groups in order; a group's vertices in batches, in parallel within a batch. The deadline is
  // checked between batches (always doing at least one): the vertices of a group read only
  // earlier groups' final values, so a group may be finished on the next call; its new values
  // are published when its last batch is done.
  bool first_batch = true;
  for (std::size_t g = state.next_group; g < order.group_end.size(); ++g) {
    const std::size_t begin = g == 0 ? 0 : order.group_end[g - 1], end = order.group_end[g];
    for (std::size_t b = std::max(begin, state.next_vertex); b < end; b += kBatch) {
      if (!first_batch && std::chrono::steady_clock::now() >= deadline) {
        state.next_group = g;
        state.next_vertex = b;
        state.residual = residual;
        return false;
      }
      first_batch = false;
      const std::size_t e = std::min(end, b + kBatch);
      if (e - b < 256)
        run(b, e);
      else
        parallel_for(e - b, 64, [&](std::size_t cb, std::size_t ce) { run(b + cb, b + ce); });
    }
    state.next_vertex = 0;
    for (std::size_t i = begin; i < end; ++i) {
      const auto v = static_cast<std::size_t>(order.vertices[i]);
      const float change = std::fabs(state.next[v] - rho1[v]);
      residual = std::max(residual, static_cast<double>(change));
      state.changed[v] = change > 0.0f;
      rho1[v] = state.next[v];
    }
  }
  state.residual = residual;
  state.in_pass = false;
  return true;
}

}  // namespace penumbra::render::lighting
