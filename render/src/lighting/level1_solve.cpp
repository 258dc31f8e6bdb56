// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level1_solve.cpp -- the tet walk and the ordered semi-Lagrangian passes
#include "level1_solve.h"

#include <algorithm>
#include <cmath>

#include "penumbra/core/elapsed.h"
#include "penumbra/core/thread_pool.h"
#include "tet_geometry.h"

namespace penumbra::render::lighting {
namespace {

// interpolate_light: optical depth interpolated up to this change across the light within a tet
// (a factor 4 in rho), rho interpolated linearly from the next (a factor 16).
constexpr double kGeometricDepth = 1.3862943611198906;
constexpr double kLinearDepth = 2.772588722239781;
// Beyond a walk's exit from the mesh, where level 0 is read: a fraction of a level-0 cell far
// above float rounding of the exit point (relative 1e-7) and far below the cell.
constexpr double kExitNudge = 1e-4;

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

VertexOrder order_vertices(const TetMesh& mesh, const Level1Topology& topology, const Light& light, double step,
                           VertexOrder reuse) {
  // This runs as one piece of a frame budget, so it avoids sorting: keys and slabs by a bucket
  // count, in parallel over fixed blocks of points. Within a slab the points keep their own order
  // (any order is valid there): the light volume numbers them along a Morton curve, so
  // consecutive walks stay in the same part of the mesh, and of memory.
  const std::size_t np = mesh.points.size();
  const Vec3d u = light.kind == Light::Kind::directional ? normalize(light.vector) : Vec3d{};
  auto used = [&](std::size_t p) { return topology.tet_offsets[p] != topology.tet_offsets[p + 1]; };
  constexpr std::size_t kBlock = 1 << 14;
  const std::size_t blocks = (np + kBlock - 1) / kBlock;
  std::vector<double> block_lo(blocks, HUGE_VAL), block_hi(blocks, -HUGE_VAL);
  std::vector<std::size_t> block_used(blocks, 0);
  VertexOrder order = std::move(reuse);
  order.vertices.clear();
  order.group_end.clear();
  order.key.resize(np);
  std::vector<double>& key = order.key;
  order.path_length.resize(np);
  parallel_for(blocks, 1, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      // Kept in locals: the threads' entries of block_lo etc. share cache lines.
      double lo = HUGE_VAL, hi = -HUGE_VAL;
      std::size_t n = 0;
      for (std::size_t p = b * kBlock; p < std::min(np, (b + 1) * kBlock); ++p) {
        key[p] = light.kind == Light::Kind::directional ? dot(mesh.points[p], u) : length(mesh.points[p] - light.vector);
        order.path_length[p] = box_path_length(mesh.bounds, mesh.points[p], light);
        if (!used(p)) continue;
        ++n;
        lo = std::min(lo, key[p]);
        hi = std::max(hi, key[p]);
      }
      block_lo[b] = lo;
      block_hi[b] = hi;
      block_used[b] = n;
    }
  });
  // Groups are the slabs [k0 + g h / 2, k0 + (g + 1) h / 2) of the key (k0 its smallest value),
  // so a bucket count replaces a sort of all points.
  const double k0 = *std::min_element(block_lo.begin(), block_lo.end());
  const double k1 = *std::max_element(block_hi.begin(), block_hi.end());
  std::size_t total = 0;
  for (std::size_t n : block_used) total += n;
  order.group_of.assign(np, -1);
  if (total == 0) return order;
  const double width = 0.5 * step;
  const auto slab_of = [&](std::size_t p) { return static_cast<std::size_t>(std::floor((key[p] - k0) / width)); };
  const double span = (k1 - k0) / width;
  order.vertices.resize(total);
  if (!(span < 2.0 * static_cast<double>(total))) {
    // Steps far below the point spacing (a user's choice): more slabs than points, so sort.
    order.vertices.clear();
    for (std::size_t p = 0; p < np; ++p)
      if (used(p)) order.vertices.push_back(static_cast<std::int32_t>(p));
    std::sort(order.vertices.begin(), order.vertices.end(), [&](std::int32_t a, std::int32_t b) {
      const std::size_t sa = slab_of(static_cast<std::size_t>(a)), sb = slab_of(static_cast<std::size_t>(b));
      return sa != sb ? sa < sb : a < b;
    });
    for (std::size_t i = 0; i < order.vertices.size(); ++i)
      if (i + 1 == order.vertices.size() || slab_of(static_cast<std::size_t>(order.vertices[i])) !=
                                                slab_of(static_cast<std::size_t>(order.vertices[i + 1])))
        order.group_end.push_back(i + 1);
    for (std::size_t g = 0, begin = 0; g < order.group_end.size(); begin = order.group_end[g++])
      for (std::size_t i = begin; i < order.group_end[g]; ++i)
        order.group_of[static_cast<std::size_t>(order.vertices[i])] = static_cast<std::int32_t>(g);
    return order;
  }
  // Each block counts its points per slab; the counts, summed in (slab, block) order, give each
  // block where its points of each slab go, so the blocks place theirs in parallel and a slab
  // keeps the points' order. With very many slabs (a step near the point spacing) the counts
  // would outgrow the points: one block then.
  const std::size_t slabs = static_cast<std::size_t>(span) + 1;
  const std::size_t parts = slabs * blocks <= 4 * np ? blocks : 1;
  const std::size_t part_size = parts == 1 ? np : kBlock;
  // [part][slab], so that the threads' counters never share a cache line: first position, after
  // the scan.
  std::vector<std::size_t> at(parts * slabs, 0);
  parallel_for(parts, 1, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b)
      for (std::size_t p = b * part_size; p < std::min(np, (b + 1) * part_size); ++p)
        if (used(p)) ++at[b * slabs + slab_of(p)];
  });
  std::vector<std::int32_t> group_of_slab(slabs, -1);
  std::size_t sum = 0;
  for (std::size_t slab = 0; slab < slabs; ++slab) {
    const std::size_t before = sum;
    for (std::size_t b = 0; b < parts; ++b) {
      const std::size_t n = at[b * slabs + slab];
      at[b * slabs + slab] = sum;
      sum += n;
    }
    if (sum > before) {
      group_of_slab[slab] = static_cast<std::int32_t>(order.group_end.size());
      order.group_end.push_back(sum);
    }
  }
  parallel_for(parts, 1, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b)
      for (std::size_t p = b * part_size; p < std::min(np, (b + 1) * part_size); ++p)
        if (used(p)) {
          const std::size_t slab = slab_of(p);
          order.vertices[at[b * slabs + slab]++] = static_cast<std::int32_t>(p);
          order.group_of[p] = group_of_slab[slab];
        }
  });
  return order;
}

// Vertices to update for which a batch wakes the other threads.
constexpr std::size_t kParallelWork = 64;

bool level1_pass(const Level1Context& ctx, const Light& light, const std::vector<float>& rho0,
                 const VertexOrder& order, std::vector<float>& rho1, PassState& state, std::atomic<std::size_t>& lost,
                 std::chrono::steady_clock::time_point deadline) {
  const TetMesh& mesh = ctx.mesh;
  const bool point = light.kind == Light::Kind::point;
  const Vec3d back = point ? Vec3d{} : -normalize(light.vector);
  const std::size_t np = rho1.size();
  state.prepare_walks(np, ctx.record_walks);
  state.changed_now.clear();
  if (!state.in_pass) {
    const auto setup_start = std::chrono::steady_clock::now();
    state.full = state.departure_corners.size() != np;
    if (state.full) {
      state.departure_corners.resize(np);
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
    state.hint_next = state.hint_end = 0;
    if (!point && state.full) {
      project_parallel(mesh, back, ctx.field.scalars, state.parallel);
      // A new light's starts from a sweep over the tets (hint_parallel_starts), in slices before
      // the first batch. Not when most starts are known or hinted: under the same light (a new
      // field or step) they are cached, and a light that moved by a little mostly keeps them.
      const auto unknown = std::count(state.start_tet.begin(), state.start_tet.end(), -1);
      if (static_cast<std::size_t>(unknown) > np / 8) {
        hint_plane(state.parallel, state.hint_xy);
        state.hint_end = ctx.topology.walk_tets.size();
      }
    }
    if (state.full)
      state.full_setup_ms = ms_since(setup_start);
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

  // A vertex being updated: its ray towards the light and, once walked or replayed, the trace.
  struct Pending {
    std::int32_t v;
    Vec3d d;
    double len;
    bool reaches_light;
    Trace tr;
  };
  // The ray of vertex v; false when its value needs no walk (then written to next).
  auto begin_update = [&](std::int32_t v, Pending& p) -> bool {
    const auto vv = static_cast<std::size_t>(v);
    const Vec3d& x = mesh.points[vv];
    for (const Bounds& box : ctx.occluders)
      if (inside_box(x, box)) {
        state.next[vv] = 0.0f;
        return false;
      }
    p = {v, back, ctx.step_of(vv), false, {}};
    if (point) {
      const Vec3d r = light.vector - x;
      const double dist = length(r);
      if (dist == 0.0) {
        state.next[vv] = 1.0f;
        return false;
      }
      p.d = r / dist;
      // Near the light rho has a cone tip no interpolation follows: walk the rest of the way.
      if (dist <= 2.0 * p.len) {
        p.len = dist;
        p.reaches_light = true;
      }
    }
    return true;
  };
  // The same walk as last time: only the extinction along it is new.
  auto replay = [&](Pending& p, const RecordedWalk& walk) {
    const std::vector<float>& scalars = ctx.field.scalars;
    auto scalar_at = [&](const WalkCrossing& c) {
      double v = 0;
      for (int j = 0; j < 3; ++j) v += static_cast<double>(c.mu[j]) * scalars[static_cast<std::size_t>(c.id[j])];
      return v;
    };
    int piece_hint = -1;
    // From the vertex itself (ray parameter 0), where every walk starts.
    double s_in = scalars[static_cast<std::size_t>(p.v)], t_in = 0;
    for (std::size_t i = 0; i < walk.count; ++i) {
      const double s_out = scalar_at(walk.crossings[i]), t_out = walk.crossings[i].t;
      p.tr.depth += ctx.field.table.integral(s_in, s_out, t_out - t_in, &piece_hint);
      s_in = s_out;
      t_in = t_out;
    }
    p.tr.kind = static_cast<Trace::Kind>(walk.kind);
    p.tr.tet = walk.tet;
    p.tr.end = p.tr.kind == Trace::Kind::inside ? p.len : static_cast<double>(walk.end);
    if (p.tr.kind == Trace::Kind::inside) {
      // The last stretch ends inside the departure tet, at the point its weights give.
      const auto& corners = topo.walk_tets[static_cast<std::size_t>(walk.tet)].v;
      double s_end = 0;
      for (int k = 0; k < 4; ++k) s_end += static_cast<double>(walk.weights[k]) * scalars[static_cast<std::size_t>(corners[k])];
      p.tr.depth += ctx.field.table.integral(s_in, s_end, p.len - t_in, &piece_hint);
    }
  };
  // Whether a walk is kept for the next passes (`keep`: walks are recorded at all), and whether
  // its crossings need a new span of the arena.
  auto worth_keeping = [](const Trace& tr) { return tr.kind != Trace::Kind::lost; };
  auto needs_span = [&](const Trace& tr, const std::vector<WalkCrossing>& walked, const RecordedWalk& walk) {
    return worth_keeping(tr) && walked.size() > walk.capacity;
  };
  // `span`: where the crossings go if the walk's own span is too small (advanced past them).
  auto keep_walk = [&](const Trace& tr, const std::vector<WalkCrossing>& walked, RecordedWalk& walk, bool keep,
                       WalkCrossing*& span) {
    walk.tet = tr.tet;
    walk.kind = static_cast<std::uint8_t>(tr.kind);
    walk.end = static_cast<float>(tr.end);
    for (int k = 0; k < 4; ++k) walk.weights[k] = tr.weights[k];
    walk.has_path = false;
    walk.valid = keep && worth_keeping(tr);
    walk.count = 0;
    if (!walk.valid) return;
    if (needs_span(tr, walked, walk)) {
      walk.crossings = span;
      walk.capacity = static_cast<std::uint32_t>(walked.size());
      span += walked.size();
    }
    std::copy(walked.begin(), walked.end(), walk.crossings);
    walk.count = static_cast<std::uint32_t>(walked.size());
  };
  // The new value of a vertex from its trace.
  auto end_update = [&](Pending& p, RecordedWalk& walk) -> float {
    const auto vv = static_cast<std::size_t>(p.v);
    const Vec3d& x = mesh.points[vv];
    Trace& tr = p.tr;
    Vec3d end = x + p.d * tr.end;
    double upstream = 0.0;
    state.departure_corners[vv] = {-1, -1, -1, -1};
    state.stale[vv] = 0;
    if (tr.kind == Trace::Kind::inside && !p.reaches_light) {
      std::copy(std::begin(topo.walk_tets[static_cast<std::size_t>(tr.tet)].v),
                std::end(topo.walk_tets[static_cast<std::size_t>(tr.tet)].v), state.departure_corners[vv].begin());
      // A corner not in an earlier group was read before its update in this pass.
      for (std::int32_t c : topo.walk_tets[static_cast<std::size_t>(tr.tet)].v)
        if (order.group_of[static_cast<std::size_t>(c)] >= order.group_of[vv]) state.stale[vv] = 1;
      upstream = departure_value(tr, end, walk);
      // A departure tet with every corner on the inflow boundary carries no extinction to
      // interpolate from: walk on to where the ray leaves the mesh bounds instead (not recorded:
      // rare, and it depends on the values).
      if (std::isnan(upstream)) {
        walk.valid = false;
        tr = walk_to_light(walk_input, p.v, x, p.d, box_path_length(mesh.bounds, x, light) * (1 + 1e-9) + 1e-300);
        end = x + p.d * tr.end;
        state.departure_corners[vv] = {-1, -1, -1, -1};
        state.stale[vv] = 0;
      }
    }
    switch (tr.kind) {
      case Trace::Kind::inside:
        if (p.reaches_light || std::isnan(upstream)) upstream = 1.0;
        break;
      case Trace::Kind::left_mesh:
        // Looked up a hair beyond the exit, on the side the light comes from: where a mesh
        // boundary lies on a plane of level-0 nodes (an axis-aligned hole), the exit point itself
        // is on a cell face, and its rounding (a recorded walk keeps it in float, the GPU works
        // in float) would pick the cell on either side; the level-0 values there differ.
        upstream = ctx.grid.sample_prefer_outside(rho0, end + p.d * (kExitNudge * ctx.grid.min_spacing()));
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
  // After the first pass: a stale read, or a departure corner that changed in this pass.
  auto needs_update = [&](std::size_t v) {
    bool dirty = state.stale[v] != 0;
    for (std::int32_t c : state.departure_corners[v]) dirty = dirty || (c >= 0 && state.changed[static_cast<std::size_t>(c)]);
    return dirty;
  };
  auto run = [&](std::size_t b, std::size_t e) {
    // In three phases, so that the fresh walks of the vertices run together (walk_batch keeps
    // several in flight and their memory loads overlap).
    struct Scratch {
      std::vector<Pending> pending;
      std::vector<WalkJob> jobs;
      std::vector<std::size_t> job_of;  // the pending entry of each job
      std::vector<std::vector<WalkCrossing>> walked;
      std::vector<RecordedWalk> unrecorded;  // walks not kept: these live for one call
    };
    // Looked up once, through a call the compiler does not see into: in a shared library every
    // use of a thread_local is a call of its own, and the compiler repeats it wherever a
    // reference to it is used.
    auto thread_scratch = []() __attribute__((noinline)) -> Scratch& {
      thread_local Scratch scratch;
      return scratch;
    };
    Scratch& own = thread_scratch();
    auto& pending = own.pending;
    auto& jobs = own.jobs;
    auto& job_of = own.job_of;
    auto& walked = own.walked;
    auto& unrecorded = own.unrecorded;
    pending.clear();
    jobs.clear();
    job_of.clear();
    for (std::size_t i = b; i < e; ++i) {
      const std::int32_t v = order.vertices[i];
      const auto vv = static_cast<std::size_t>(v);
      // After the first pass a vertex whose inputs are unchanged keeps its value: only stale
      // reads and the vertices downstream of a change are recomputed.
      const bool recompute = full || needs_update(vv);
      if (!recompute) {
        state.next[vv] = rho1[vv];
        continue;
      }
      Pending p;
      if (begin_update(v, p)) pending.push_back(p);
    }
    const bool keep = !state.walks.empty();
    if (!keep) {
      unrecorded.resize(pending.size());
      for (RecordedWalk& w : unrecorded) w.valid = false;
    }
    auto walk_of = [&](std::size_t j) -> RecordedWalk& {
      return keep ? state.walks[static_cast<std::size_t>(pending[j].v)] : unrecorded[j];
    };
    if (walked.size() < pending.size()) walked.resize(pending.size());
    for (std::size_t j = 0; j < pending.size(); ++j) {
      Pending& p = pending[j];
      const RecordedWalk& walk = walk_of(j);
      if (walk.valid) {
        replay(p, walk);
        continue;
      }
      walked[jobs.size()].clear();
      jobs.push_back({p.v, mesh.points[static_cast<std::size_t>(p.v)], p.d, p.len,
                      &state.start_tet[static_cast<std::size_t>(p.v)], &walked[jobs.size()], {}});
      job_of.push_back(j);
    }
    walk_batch(walk_input, jobs.data(), jobs.size());
    // One span of the arena for every walk here that does not fit its own.
    std::size_t need = 0;
    if (keep)
      for (std::size_t k = 0; k < jobs.size(); ++k)
        if (needs_span(jobs[k].trace, walked[k], walk_of(job_of[k]))) need += walked[k].size();
    WalkCrossing* span = need > 0 ? state.crossings.allocate(need) : nullptr;
    for (std::size_t k = 0; k < jobs.size(); ++k) {
      pending[job_of[k]].tr = jobs[k].trace;
      keep_walk(jobs[k].trace, walked[k], walk_of(job_of[k]), keep, span);
    }
    for (std::size_t j = 0; j < pending.size(); ++j)
      state.next[static_cast<std::size_t>(pending[j].v)] = end_update(pending[j], walk_of(j));
  };
  double residual = state.residual;
  // Groups in order; a group's vertices in batches, in parallel within a batch. Between batches
  // (always doing at least one) the next starts only if it is expected to end by the deadline:
  // the vertices of a group read only earlier groups' final values, so a group may be finished
  // on the next call; its new values are published when its last batch is done.
  bool first_batch = true;
  while (state.hint_next < state.hint_end) {
    const auto now = std::chrono::steady_clock::now();
    if (!first_batch && state.hint_slice_ms > 0 &&
        std::chrono::duration<double, std::milli>(deadline - now).count() < state.hint_slice_ms)
      return false;
    first_batch = false;
    const std::size_t e = std::min(state.hint_end, state.hint_next + kHintSlice);
    hint_parallel_starts(ctx.topology.walk_tets, state.hint_xy, state.hint_next, e, state.start_tet);
    state.hint_next = e;
    state.hint_slice_ms = ms_since(now);
  }
  for (std::size_t g = state.next_group; g < order.group_end.size(); ++g) {
    const std::size_t begin = g == 0 ? 0 : order.group_end[g - 1], end = order.group_end[g];
    for (std::size_t b = std::max(begin, state.next_vertex); b < end;) {
      std::size_t e = std::min(end, b + kLevel1Batch);
      const auto now = std::chrono::steady_clock::now();
      if (deadline != std::chrono::steady_clock::time_point::max()) {
        // The batch shrinks to what is expected to fit before the deadline (a whole one or none
        // would leave half a batch of each frame's budget unused on average). The call's first batch
        // always runs, so that every call makes progress, down to kLevel1MinBatch vertices (a
        // pass may start with little of the budget left), and whole if never timed. After it,
        // a batch too small to be worth waking the threads for waits for the next call, and so
        // does one never timed (after the start hints, the first batch of a pass: its first
        // vertices, on the side the light enters, leave the mesh at once, so a small probe
        // would time them far too fast).
        const double left_ms = std::chrono::duration<double, std::milli>(deadline - now).count();
        const double fits = state.vertex_ms > 0 ? left_ms / state.vertex_ms : first_batch ? HUGE_VAL : 0.0;
        if (!first_batch && fits < static_cast<double>(std::min(e - b, kLevel1MinBatch))) {
          state.next_group = g;
          state.next_vertex = b;
          state.residual = residual;
          return false;
        }
        const double room = std::max(fits, first_batch ? static_cast<double>(kLevel1MinBatch) : 0.0);
        if (room < static_cast<double>(e - b)) e = b + static_cast<std::size_t>(room);
      }
      first_batch = false;
      // After the first pass most batches hold a few vertices to update, if any: the threads are
      // woken only for enough work, since waking them per group costs a few ms per pass. A
      // vertex to update is a walk of a microsecond or more, so a few dozen are worth it, and a
      // larger threshold would leave the smallest groups on one thread.
      std::size_t work = e - b;
      if (!full) {
        work = 0;
        for (std::size_t i = b; i < e && work < kParallelWork; ++i)
          work += needs_update(static_cast<std::size_t>(order.vertices[i]));
      }
      if (work < kParallelWork)
        run(b, e);
      else
        parallel_for(e - b, kParallelWork / 2, [&](std::size_t cb, std::size_t ce) { run(b + cb, b + ce); });
      const double per_vertex = ms_since(now) / static_cast<double>(e - b);
      state.vertex_ms = state.vertex_ms < 0 ? per_vertex : 0.5 * (state.vertex_ms + per_vertex);
      b = e;
    }
    state.next_vertex = 0;
    for (std::size_t i = begin; i < end; ++i) {
      const auto v = static_cast<std::size_t>(order.vertices[i]);
      const float change = std::fabs(state.next[v] - rho1[v]);
      residual = std::max(residual, static_cast<double>(change));
      state.changed[v] = change > 0.0f;
      if (!(state.next[v] == rho1[v])) state.changed_now.push_back(static_cast<std::int32_t>(v));
      rho1[v] = state.next[v];
    }
  }
  state.residual = residual;
  state.in_pass = false;
  return true;
}

}  // namespace penumbra::render::lighting
