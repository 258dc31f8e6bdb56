// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level1_pass.cpp -- one ordered semi-Lagrangian pass of level 1 (eq. 6-8)
#include <algorithm>
#include <cmath>
#include <optional>

#include "level1_solve.h"
#include "penumbra/core/elapsed.h"
#include "penumbra/core/thread_pool.h"
#include "tet_geometry.h"

namespace penumbra::render::lighting {
namespace {

using Clock = std::chrono::steady_clock;

// Beyond a walk's exit from the mesh, where level 0 is read: a fraction of a level-0 cell far
// above float rounding of the exit point (relative 1e-7) and far below the cell.
constexpr double kExitNudge = 1e-4;
// Vertices to update for which a batch wakes the other threads.
constexpr std::size_t kParallelWork = 64;

// A vertex being updated: its ray towards the light and, once walked or replayed, the trace.
struct Pending {
  std::int32_t v;
  Vec3d d;
  double len;
  bool reaches_light;
  Trace tr;
};

// A batch's working memory, one per thread, kept from batch to batch.
struct Scratch {
  std::vector<Pending> pending;
  std::vector<WalkJob> jobs;
  std::vector<std::size_t> job_of;  // the pending entry of each job
  std::vector<std::vector<WalkCrossing>> walked;
  std::vector<RecordedWalk> unrecorded;  // walks not kept: these live for one call
};

// Looked up once per batch, through a call the compiler does not see into: in a shared library
// every use of a thread_local is a call of its own, and the compiler repeats it wherever a
// reference to it is used.
[[gnu::noinline]] Scratch& thread_scratch() {
  thread_local Scratch scratch;
  return scratch;
}

// Whether a walk is kept for the next passes (when walks are recorded at all), and whether its
// crossings need a new span of the arena.
bool worth_keeping(const Trace& tr) { return tr.kind != Trace::Kind::lost; }
bool needs_span(const Trace& tr, const std::vector<WalkCrossing>& walked, const RecordedWalk& walk) {
  return worth_keeping(tr) && walked.size() > walk.capacity;
}

// Records walk `tr` with its crossings `walked` in `walk` (valid only if `keep`). `span`: where the
// crossings go if the walk's own span is too small (advanced past them).
void keep_walk(const Trace& tr, const std::vector<WalkCrossing>& walked, RecordedWalk& walk, bool keep,
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
}

// A pass that starts: which vertices it recomputes (every one after a reset), and a directional
// light's projections and start hints.
void start_pass(const Level1Context& ctx, bool point, const Vec3d& back, std::size_t np, PassState& state) {
  const auto setup_start = Clock::now();
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
    project_parallel(ctx.mesh, back, ctx.field.scalars, state.parallel);
    // A new light's starts from a sweep over the tets (hint_parallel_starts), in slices before
    // the first batch. Not when most starts are known or hinted: under the same light (a new
    // field or step) they are cached, and a light that moved by a little mostly keeps them.
    const auto unknown = std::count(state.start_tet.begin(), state.start_tet.end(), -1);
    if (static_cast<std::size_t>(unknown) > np / 8) {
      hint_plane(state.parallel, state.hint_xy);
      state.hint_end = ctx.topology.walk_tets.size();
    }
  }
  if (state.full) state.full_setup_ms = ms_since(setup_start);
}

// One call of level1_pass after its set-up: the pass's inputs, and the updates of its vertices.
class PassRun {
public:
  PassRun(const Level1Context& ctx, const Light& light, const Vec3d& back, const std::vector<float>& rho0,
          const VertexOrder& order, std::vector<float>& rho1, PassState& state, std::atomic<std::size_t>& lost)
      : m_ctx(ctx),
        m_mesh(ctx.mesh),
        m_topo(ctx.topology),
        m_light(light),
        m_point(light.kind == Light::Kind::point),
        m_back(back),
        m_rho0(rho0),
        m_order(order),
        m_rho1(rho1),
        m_state(state),
        m_lost(lost),
        m_full(state.full),
        m_walk_input{m_topo.walk_tets, m_topo.tet_offsets, m_topo.star, ctx.field.table,
                     m_point ? nullptr : state.parallel.data(), m_mesh.points.data(), ctx.field.scalars.data()} {}

  bool make_start_hints(Clock::time_point deadline, bool& first_batch);
  bool run_groups(Clock::time_point deadline, bool& first_batch);

private:
  std::optional<std::size_t> batch_end(std::size_t b, std::size_t end, Clock::time_point deadline,
                                       Clock::time_point now, bool first_batch) const;
  void run_batch(std::size_t b, std::size_t e);
  void run_batch_on_threads(std::size_t b, std::size_t e);
  void publish_group(std::size_t begin, std::size_t end, double& residual);
  bool needs_update(std::size_t v) const;
  void gather_updates(std::size_t b, std::size_t e, std::vector<Pending>& pending);
  bool begin_update(std::int32_t v, Pending& p);
  RecordedWalk& walk_of(Scratch& own, bool keep, std::size_t j);
  void trace_updates(Scratch& own, bool keep);
  void store_fresh_walks(Scratch& own, bool keep);
  void replay(Pending& p, const RecordedWalk& walk) const;
  float end_update(Pending& p, RecordedWalk& walk);
  double departure_tet_value(Pending& p, RecordedWalk& walk, Vec3d& end);
  double departure_value(const Trace& tr, const Vec3d& end, RecordedWalk& walk) const;
  double outside_value(const Pending& p, const Vec3d& end, double upstream);

  const Level1Context& m_ctx;
  const TetMesh& m_mesh;
  const Level1Topology& m_topo;
  const Light& m_light;
  const bool m_point;
  const Vec3d m_back;
  const std::vector<float>& m_rho0;
  const VertexOrder& m_order;
  std::vector<float>& m_rho1;
  PassState& m_state;
  std::atomic<std::size_t>& m_lost;
  const bool m_full;
  const WalkInput m_walk_input;
};

// A new directional light's start hints, in slices, each only if it is expected to end by the
// deadline (the call's first piece always runs).
bool PassRun::make_start_hints(Clock::time_point deadline, bool& first_batch) {
  while (m_state.hint_next < m_state.hint_end) {
    const auto now = Clock::now();
    if (!first_batch && m_state.hint_slice_ms > 0 &&
        std::chrono::duration<double, std::milli>(deadline - now).count() < m_state.hint_slice_ms)
      return false;
    first_batch = false;
    const std::size_t e = std::min(m_state.hint_end, m_state.hint_next + kHintSlice);
    hint_parallel_starts(m_topo.walk_tets, m_state.hint_xy, m_state.hint_next, e, m_state.start_tet);
    m_state.hint_next = e;
    m_state.hint_slice_ms = ms_since(now);
  }
  return true;
}

// Groups in order; a group's vertices in batches, in parallel within a batch. Between batches
// (always doing at least one) the next starts only if it is expected to end by the deadline:
// the vertices of a group read only earlier groups' final values, so a group may be finished
// on the next call; its new values are published when its last batch is done.
bool PassRun::run_groups(Clock::time_point deadline, bool& first_batch) {
  double residual = m_state.residual;
  for (std::size_t g = m_state.next_group; g < m_order.group_end.size(); ++g) {
    const std::size_t begin = g == 0 ? 0 : m_order.group_end[g - 1], end = m_order.group_end[g];
    for (std::size_t b = std::max(begin, m_state.next_vertex); b < end;) {
      const auto now = Clock::now();
      const std::optional<std::size_t> e = batch_end(b, end, deadline, now, first_batch);
      if (!e) {
        m_state.next_group = g;
        m_state.next_vertex = b;
        m_state.residual = residual;
        return false;
      }
      first_batch = false;
      run_batch_on_threads(b, *e);
      const double per_vertex = ms_since(now) / static_cast<double>(*e - b);
      m_state.vertex_ms = m_state.vertex_ms < 0 ? per_vertex : 0.5 * (m_state.vertex_ms + per_vertex);
      b = *e;
    }
    m_state.next_vertex = 0;
    publish_group(begin, end, residual);
  }
  m_state.residual = residual;
  m_state.in_pass = false;
  return true;
}

// Where the batch from vertex b of a group ending at `end` ends; none: it waits for the next
// call. The batch shrinks to what is expected to fit before the deadline (a whole one or none
// would leave half a batch of each frame's budget unused on average). The call's first batch
// always runs, so that every call makes progress, down to kLevel1MinBatch vertices (a pass may
// start with little of the budget left), and whole if never timed. After it, a batch too small
// to be worth waking the threads for waits for the next call, and so does one never timed
// (after the start hints, the first batch of a pass: its first vertices, on the side the light
// enters, leave the mesh at once, so a small probe would time them far too fast).
std::optional<std::size_t> PassRun::batch_end(std::size_t b, std::size_t end, Clock::time_point deadline,
                                              Clock::time_point now, bool first_batch) const {
  std::size_t e = std::min(end, b + kLevel1Batch);
  if (deadline == Clock::time_point::max()) return e;
  const double left_ms = std::chrono::duration<double, std::milli>(deadline - now).count();
  const double fits = m_state.vertex_ms > 0 ? left_ms / m_state.vertex_ms : first_batch ? HUGE_VAL : 0.0;
  if (!first_batch && fits < static_cast<double>(std::min(e - b, kLevel1MinBatch))) return std::nullopt;
  const double room = std::max(fits, first_batch ? static_cast<double>(kLevel1MinBatch) : 0.0);
  if (room < static_cast<double>(e - b)) e = b + static_cast<std::size_t>(room);
  return e;
}

// After the first pass most batches hold a few vertices to update, if any: the threads are
// woken only for enough work, since waking them per group costs a few ms per pass. A vertex to
// update is a walk of a microsecond or more, so a few dozen are worth it, and a larger
// threshold would leave the smallest groups on one thread.
void PassRun::run_batch_on_threads(std::size_t b, std::size_t e) {
  std::size_t work = e - b;
  if (!m_full) {
    work = 0;
    for (std::size_t i = b; i < e && work < kParallelWork; ++i)
      work += needs_update(static_cast<std::size_t>(m_order.vertices[i]));
  }
  if (work < kParallelWork)
    run_batch(b, e);
  else
    parallel_for(e - b, kParallelWork / 2, [&](std::size_t cb, std::size_t ce) { run_batch(b + cb, b + ce); });
}

// A finished group's new values become the pass's, with their largest change.
void PassRun::publish_group(std::size_t begin, std::size_t end, double& residual) {
  for (std::size_t i = begin; i < end; ++i) {
    const auto v = static_cast<std::size_t>(m_order.vertices[i]);
    const float change = std::fabs(m_state.next[v] - m_rho1[v]);
    residual = std::max(residual, static_cast<double>(change));
    m_state.changed[v] = change > 0.0f;
    if (!(m_state.next[v] == m_rho1[v])) m_state.changed_now.push_back(static_cast<std::int32_t>(v));
    m_rho1[v] = m_state.next[v];
  }
}

// After the first pass: a stale read, or a departure corner that changed in this pass.
bool PassRun::needs_update(std::size_t v) const {
  bool dirty = m_state.stale[v] != 0;
  for (std::int32_t c : m_state.departure_corners[v])
    dirty = dirty || (c >= 0 && m_state.changed[static_cast<std::size_t>(c)]);
  return dirty;
}

// Vertices [b, e) of the order, in three phases, so that the fresh walks of the vertices run
// together (walk_batch keeps several in flight and their memory loads overlap).
void PassRun::run_batch(std::size_t b, std::size_t e) {
  Scratch& own = thread_scratch();
  gather_updates(b, e, own.pending);
  const bool keep = !m_state.walks.empty();
  if (!keep) {
    own.unrecorded.resize(own.pending.size());
    for (RecordedWalk& w : own.unrecorded) w.valid = false;
  }
  trace_updates(own, keep);
  for (std::size_t j = 0; j < own.pending.size(); ++j)
    m_state.next[static_cast<std::size_t>(own.pending[j].v)] = end_update(own.pending[j], walk_of(own, keep, j));
}

// The vertices of [b, e) to recompute, with their rays. After the first pass a vertex whose
// inputs are unchanged keeps its value: only stale reads and the vertices downstream of a change
// are recomputed.
void PassRun::gather_updates(std::size_t b, std::size_t e, std::vector<Pending>& pending) {
  pending.clear();
  for (std::size_t i = b; i < e; ++i) {
    const std::int32_t v = m_order.vertices[i];
    const auto vv = static_cast<std::size_t>(v);
    if (!m_full && !needs_update(vv)) {
      m_state.next[vv] = m_rho1[vv];
      continue;
    }
    Pending p;
    if (begin_update(v, p)) pending.push_back(p);
  }
}

// The ray of vertex v; false when its value needs no walk (then written to next).
bool PassRun::begin_update(std::int32_t v, Pending& p) {
  const auto vv = static_cast<std::size_t>(v);
  const Vec3d& x = m_mesh.points[vv];
  for (const Bounds& box : m_ctx.occluders)
    if (inside_box(x, box)) {
      m_state.next[vv] = 0.0f;
      return false;
    }
  p = {v, m_back, m_ctx.step_of(vv), false, {}};
  if (m_point) {
    const Vec3d r = m_light.vector - x;
    const double dist = length(r);
    if (dist == 0.0) {
      m_state.next[vv] = 1.0f;
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
}

RecordedWalk& PassRun::walk_of(Scratch& own, bool keep, std::size_t j) {
  return keep ? m_state.walks[static_cast<std::size_t>(own.pending[j].v)] : own.unrecorded[j];
}

// Every pending vertex's trace: replayed along its recorded walk, or walked anew (in one batch)
// and recorded.
void PassRun::trace_updates(Scratch& own, bool keep) {
  own.jobs.clear();
  own.job_of.clear();
  if (own.walked.size() < own.pending.size()) own.walked.resize(own.pending.size());
  for (std::size_t j = 0; j < own.pending.size(); ++j) {
    Pending& p = own.pending[j];
    const RecordedWalk& walk = walk_of(own, keep, j);
    if (walk.valid) {
      replay(p, walk);
      continue;
    }
    own.walked[own.jobs.size()].clear();
    own.jobs.push_back({p.v, m_mesh.points[static_cast<std::size_t>(p.v)], p.d, p.len,
                        &m_state.start_tet[static_cast<std::size_t>(p.v)], &own.walked[own.jobs.size()], {}});
    own.job_of.push_back(j);
  }
  walk_batch(m_walk_input, own.jobs.data(), own.jobs.size());
  store_fresh_walks(own, keep);
}

// The fresh walks' traces to their vertices, and their crossings to the records: one span of the
// arena for every walk here that does not fit its own.
void PassRun::store_fresh_walks(Scratch& own, bool keep) {
  std::size_t need = 0;
  if (keep)
    for (std::size_t k = 0; k < own.jobs.size(); ++k)
      if (needs_span(own.jobs[k].trace, own.walked[k], walk_of(own, keep, own.job_of[k]))) need += own.walked[k].size();
  WalkCrossing* span = need > 0 ? m_state.crossings.allocate(need) : nullptr;
  for (std::size_t k = 0; k < own.jobs.size(); ++k) {
    own.pending[own.job_of[k]].tr = own.jobs[k].trace;
    keep_walk(own.jobs[k].trace, own.walked[k], walk_of(own, keep, own.job_of[k]), keep, span);
  }
}

// The same walk as last time: only the extinction along it is new.
void PassRun::replay(Pending& p, const RecordedWalk& walk) const {
  const std::vector<float>& scalars = m_ctx.field.scalars;
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
    p.tr.depth += m_ctx.field.table.integral(s_in, s_out, t_out - t_in, &piece_hint);
    s_in = s_out;
    t_in = t_out;
  }
  p.tr.kind = static_cast<Trace::Kind>(walk.kind);
  p.tr.tet = walk.tet;
  p.tr.end = p.tr.kind == Trace::Kind::inside ? p.len : static_cast<double>(walk.end);
  if (p.tr.kind == Trace::Kind::inside) {
    // The last stretch ends inside the departure tet, at the point its weights give.
    const auto& corners = m_topo.walk_tets[static_cast<std::size_t>(walk.tet)].v;
    double s_end = 0;
    for (int k = 0; k < 4; ++k) s_end += static_cast<double>(walk.weights[k]) * scalars[static_cast<std::size_t>(corners[k])];
    p.tr.depth += m_ctx.field.table.integral(s_in, s_end, p.len - t_in, &piece_hint);
  }
}

// The new value of a vertex from its trace: the light upstream, attenuated along the trace.
float PassRun::end_update(Pending& p, RecordedWalk& walk) {
  const auto vv = static_cast<std::size_t>(p.v);
  const Vec3d& x = m_mesh.points[vv];
  Vec3d end = x + p.d * p.tr.end;
  double upstream = 0.0;
  m_state.departure_corners[vv] = {-1, -1, -1, -1};
  m_state.stale[vv] = 0;
  if (p.tr.kind == Trace::Kind::inside && !p.reaches_light) upstream = departure_tet_value(p, walk, end);
  upstream = outside_value(p, end, upstream);
  for (const Bounds& box : m_ctx.occluders)
    if (segment_meets_box(x, end, box)) return 0.0f;
  return static_cast<float>(flush(upstream * std::exp(-m_ctx.sigma_a * p.tr.depth)));
}

// The light at a departure point inside the mesh, from its tet's corners, noting which corners
// the vertex read before their update in this pass. NaN when the walk had to go on to the mesh
// bounds (then p.tr and `end` are that walk's).
double PassRun::departure_tet_value(Pending& p, RecordedWalk& walk, Vec3d& end) {
  const auto vv = static_cast<std::size_t>(p.v);
  const Vec3d& x = m_mesh.points[vv];
  const auto& corners = m_topo.walk_tets[static_cast<std::size_t>(p.tr.tet)].v;
  std::copy(std::begin(corners), std::end(corners), m_state.departure_corners[vv].begin());
  // A corner not in an earlier group was read before its update in this pass.
  for (std::int32_t c : corners)
    if (m_order.group_of[static_cast<std::size_t>(c)] >= m_order.group_of[vv]) m_state.stale[vv] = 1;
  const double upstream = departure_value(p.tr, end, walk);
  // A departure tet with every corner on the inflow boundary carries no extinction to
  // interpolate from: walk on to where the ray leaves the mesh bounds instead (not recorded:
  // rare, and it depends on the values).
  if (std::isnan(upstream)) {
    walk.valid = false;
    p.tr = walk_to_light(m_walk_input, p.v, x, p.d, box_path_length(m_mesh.bounds, x, m_light) * (1 + 1e-9) + 1e-300);
    end = x + p.d * p.tr.end;
    m_state.departure_corners[vv] = {-1, -1, -1, -1};
    m_state.stale[vv] = 0;
  }
  return upstream;
}

// rho at a departure point inside its tet (interpolate_light).
double PassRun::departure_value(const Trace& tr, const Vec3d& end, RecordedWalk& walk) const {
  if (!walk.has_path) {
    walk.path = box_path_length(m_mesh.bounds, end, m_light);
    walk.has_path = true;
  }
  const std::array<double, 4> w{walk.weights[0], walk.weights[1], walk.weights[2], walk.weights[3]};
  const auto& tv = m_topo.walk_tets[static_cast<std::size_t>(tr.tet)].v;
  double values[4], path[4];
  Vec3d corner[4];
  for (int k = 0; k < 4; ++k) {
    const auto c = static_cast<std::size_t>(tv[k]);
    values[k] = m_rho1[c];
    corner[k] = m_mesh.points[c];
    path[k] = m_order.path_length[c];
  }
  const Vec3d u = m_point ? normalize(end - m_light.vector) : -m_back;
  return interpolate_light(w, values, path, walk.path, corner, u);
}

// The light upstream of a trace by how it ended: at the light (1), inside the mesh (`upstream`,
// from departure_tet_value), or where it left the mesh or was lost (level 0).
double PassRun::outside_value(const Pending& p, const Vec3d& end, double upstream) {
  switch (p.tr.kind) {
    case Trace::Kind::inside:
      return p.reaches_light || std::isnan(upstream) ? 1.0 : upstream;
    case Trace::Kind::left_mesh:
      // Looked up a hair beyond the exit, on the side the light comes from: where a mesh
      // boundary lies on a plane of level-0 nodes (an axis-aligned hole), the exit point itself
      // is on a cell face, and its rounding (a recorded walk keeps it in float, the GPU works
      // in float) would pick the cell on either side; the level-0 values there differ.
      return m_ctx.grid.sample_prefer_outside(m_rho0, end + p.d * (kExitNudge * m_ctx.grid.min_spacing()));
    default:
      m_lost.fetch_add(1, std::memory_order_relaxed);
      return m_ctx.grid.sample(m_rho0, end);
  }
}

}  // namespace

bool level1_pass(const Level1Context& ctx, const Light& light, const std::vector<float>& rho0,
                 const VertexOrder& order, std::vector<float>& rho1, PassState& state, std::atomic<std::size_t>& lost,
                 std::chrono::steady_clock::time_point deadline) {
  const bool point = light.kind == Light::Kind::point;
  const Vec3d back = point ? Vec3d{} : -normalize(light.vector);
  const std::size_t np = rho1.size();
  state.prepare_walks(np, ctx.record_walks);
  state.changed_now.clear();
  if (!state.in_pass) start_pass(ctx, point, back, np, state);
  PassRun run(ctx, light, back, rho0, order, rho1, state, lost);
  bool first_batch = true;
  return run.make_start_hints(deadline, first_batch) && run.run_groups(deadline, first_batch);
}

}  // namespace penumbra::render::lighting
