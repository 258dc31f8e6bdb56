// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level1_walk.cpp -- the level-1 walk by edge signs in the plane across the ray
#include "level1_walk.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>

#include "penumbra/core/thread_pool.h"
#include "shader_constants.h"

namespace penumbra::render::lighting {
namespace {

using detail::edge_positive;
using detail::edge_value;
using detail::kAbc;
using detail::kExitX;
using detail::kFaceVertices;
using detail::Projected;
using detail::WalkTet;

// Edge values within this fraction of the edge's squared size (|q_a|^2 + |q_b|^2 in the plane)
// are rounding noise around an exact zero: a ray that really runs along an edge or a face (an
// axis-aligned or diagonal light on a structured mesh) is projected through an irrational frame,
// and its edge values come out as +-1e-17 instead of 0. A walk that could not start by such
// noise is retried with them snapped to 0 (walk_turned), where the tie rule decides.
constexpr double kSnap = 1e-12;

// A walk of one step crosses about step / edge tets; this cap only stops a walk that cycles in
// a degenerate configuration (it then falls back to level 0 and is counted).
using shader::kMaxMoves;

// Rays parallel to a directional light: projections shared by every walk of the light, taken
// relative to the walk's own start.
struct ParallelRays {
  static constexpr bool kSnaps = false;  // see TurnedRays
  const ParallelPoint* points;
  ParallelPoint origin;
  Projected at(std::int32_t id) const {
    const ParallelPoint& p = points[id];
    return {p.x - origin.x, p.y - origin.y, p.depth - origin.depth};
  }
  double scalar(std::int32_t id) const { return points[id].s; }
  void prefetch(std::int32_t id) const { __builtin_prefetch(points + id); }
};

// Rays converging on a point light: each walk projects the points it meets into its own frame.
struct ConvergingRays {
  static constexpr bool kSnaps = false;  // see TurnedRays
  detail::RayFrame frame;
  const Vec3d* points;
  const float* scalars;
  Projected at(std::int32_t id) const { return frame.project(points[id]); }
  double scalar(std::int32_t id) const { return scalars[id]; }
  void prefetch(std::int32_t id) const {
    __builtin_prefetch(points + id);
    __builtin_prefetch(scalars + id);
  }
};

// The rays turned by a quarter turn (0 to 3) in the plane across them. The tie rule displaces
// every ray by (eps, eps^2) in its plane; turning the plane turns that displacement, so each
// quarter pushes a ray lying in the mesh boundary to another side of it (see walk_turned).
// (Turning by quarters is exact: it permutes and negates coordinates, and every edge value
// keeps its products.)
template <class Rays>
struct TurnedRays {
  // Its walks are retries: edge values within rounding noise of 0 are snapped to 0 (Walker::edge).
  static constexpr bool kSnaps = true;
  Rays rays;
  int quarter;
  Projected at(std::int32_t id) const {
    const Projected p = rays.at(id);
    if (quarter == 0) return p;
    if (quarter == 1) return {-p.y, p.x, p.depth};
    if (quarter == 2) return {-p.x, -p.y, p.depth};
    return {p.y, -p.x, p.depth};
  }
  double scalar(std::int32_t id) const { return rays.scalar(id); }
  void prefetch(std::int32_t id) const { rays.prefetch(id); }
};

// Where the ray crosses a face: the face's points and their weights (summing to 1).
struct Crossing {
  std::int32_t id[3];
  double mu[3];
  double t, s;
};

// The crossing of the face with points id (projected q) from unnormalised weights w (>= 0);
// with all weights 0 (the ray in the face's plane) the ray is still where it was, at `from`.
// Inlined, so that the crossings stay in registers instead of passing through memory.
template <class Rays>
[[gnu::always_inline]] inline Crossing cross_face(const Rays& rays, const std::int32_t id[3], const Projected q[3],
                                                  const double w[3], const Crossing& from) {
  const double sum = w[0] + w[1] + w[2];
  if (!(sum > 0)) return from;
  Crossing c{{id[0], id[1], id[2]}, {0, 0, 0}, 0.0, 0.0};
  const double inv = 1.0 / sum;
  for (int j = 0; j < 3; ++j) {
    c.mu[j] = w[j] * inv;
    c.t += c.mu[j] * q[j].depth;
    c.s += c.mu[j] * rays.scalar(id[j]);
  }
  c.t = std::max(c.t, from.t);
  return c;
}

// One walk for one set of rays, resumable step by step so that a thread can keep several in
// flight (walk_batch): each step's loads then overlap other walks' work instead of stalling.
// `grazed` is set when it cannot start only by the tie rule: the unperturbed ray touches a face
// of v's star opposite v on its rim, so it runs along the boundary of the closed mesh.
template <class Rays>
class Walker {
public:
  Walker(const WalkInput& in, const Rays& rays, std::int32_t v, double length, std::vector<WalkCrossing>* record)
      : m_in(in), m_rays(rays), m_v(v), m_length(length), m_record(record) {}

  // Finds the start and enters the first tet, all at once; false: the walk is already over
  // (see trace()). Then step() until it returns false.
  bool start(std::int32_t* cache) {
    if (!begin(cache)) return false;
    while (m_phase != Phase::peek)
      if (!advance()) return false;
    return true;
  }

  // The same walk in small phases, for walk_batch: each phase prefetches what the next one reads
  // (the vertex's star, the points of its faces, the next tet, the new point of the next tet), so
  // that its load overlaps the phases of the other walks in flight instead of stalling. begin()
  // false: the walk is already over; then advance() until it returns false.
  bool begin(std::int32_t* cache) {
    m_cache = cache;
    if (cache && *cache == -2) {
      m_tr.kind = Trace::Kind::left_mesh;
      return false;
    }
    if (cache && (*cache >= 0 || *cache <= kFirstHint)) {
      const std::int32_t record = *cache >= 0 ? *cache : kFirstHint - *cache;
      m_slot = record >> 2;
      m_k = record & 3;
      __builtin_prefetch(&m_in.tets[static_cast<std::size_t>(m_slot)]);
      m_phase = *cache >= 0 ? Phase::cached : Phase::hinted;
      return true;
    }
    search_star();
    return true;
  }

  bool advance() {
    switch (m_phase) {
      case Phase::offsets: {
        m_star_begin = m_in.star_offsets[static_cast<std::size_t>(m_v)];
        m_star_end = m_in.star_offsets[static_cast<std::size_t>(m_v) + 1];
        const char* first = reinterpret_cast<const char*>(m_in.star.data() + m_star_begin);
        const char* last = reinterpret_cast<const char*>(m_in.star.data() + m_star_end);
        for (const char* line = first; line < last; line += 64) __builtin_prefetch(line);
        if (last > first) __builtin_prefetch(last - 1);
        m_phase = Phase::star;
        return true;
      }
      case Phase::star:
        for (auto s = m_star_begin; s < m_star_end; ++s)
          for (std::int32_t id : m_in.star[static_cast<std::size_t>(s)].v) m_rays.prefetch(id);
        m_phase = Phase::scan;
        return true;
      case Phase::scan:
        for (auto s = m_star_begin; s < m_star_end; ++s) {
          const StarFace& f = m_in.star[static_cast<std::size_t>(s)];
          if (leaves_through(f.v)) {
            m_slot = f.record >> 2;
            m_k = f.record & 3;
            break;
          }
        }
        if (m_cache) *m_cache = m_slot < 0 ? -2 : (m_slot << 2 | m_k);
        if (m_slot < 0) {
          m_tr.kind = Trace::Kind::left_mesh;
          return false;
        }
        __builtin_prefetch(&m_in.tets[static_cast<std::size_t>(m_slot)]);
        m_phase = Phase::enter;
        return true;
      case Phase::cached:
      case Phase::hinted: {
        // The start's face: known (cached; only the crossing is wanted), or a hint, the start for
        // a nearby direction, most often still the start.
        const WalkTet& w = m_in.tets[static_cast<std::size_t>(m_slot)];
        const std::int32_t face[3] = {w.v[kFaceVertices[m_k][0]], w.v[kFaceVertices[m_k][1]], w.v[kFaceVertices[m_k][2]]};
        if (leaves_through(face) || m_phase == Phase::cached) {
          *m_cache = m_slot << 2 | m_k;
          m_phase = Phase::enter;
        } else {
          // Not it: the search decides, grazes included.
          m_grazed = false;
          m_slot = m_k = -1;
          search_star();
        }
        return true;
      }
      case Phase::enter:
        m_grazed = false;
        m_enter = {{m_v, m_v, m_v}, {1, 0, 0}, 0.0, m_rays.scalar(m_v)};
        m_next = m_in.tets[static_cast<std::size_t>(m_slot)].next[m_k];
        if (m_next >= 0) __builtin_prefetch(&m_in.tets[static_cast<std::size_t>(m_next >> 2)]);
        m_phase = Phase::peek;
        return true;
      case Phase::peek:
        // The next tet's record arrived while the other walks ran: its point opposite the entry
        // face is the one the step reads that is not in cache yet.
        if (m_next >= 0 && m_out.t < m_length) m_rays.prefetch(m_in.tets[static_cast<std::size_t>(m_next >> 2)].v[m_next & 3]);
        m_phase = Phase::step;
        return true;
      case Phase::step:
        m_phase = Phase::peek;
        return step();
    }
    return false;
  }

  // Integrates the current tet's segment and moves on; false: the walk is over.
  bool step() {
    if (m_out.t >= m_length) {
      finish_inside();
      return false;
    }
    m_tr.depth += m_in.table.integral(m_enter.s, m_out.s, m_out.t - m_enter.t, &m_piece_hint);
    keep(m_out);
    if (m_next < 0) {
      m_tr.kind = Trace::Kind::left_mesh;
      m_tr.tet = m_slot;
      m_tr.end = m_out.t;
      return false;
    }
    if (++m_moves >= kMaxMoves) {
      m_tr.kind = Trace::Kind::lost;
      m_tr.tet = m_slot;
      m_tr.end = m_length;
      return false;
    }
    // The next tet, entered through face k: leave through the face (D, X, Y) picked by the signs
    // of the edges from D, the vertex opposite the entry.
    m_slot = m_next >> 2;
    m_k = m_next & 3;
    m_enter = m_out;
    const WalkTet& w = m_in.tets[static_cast<std::size_t>(m_slot)];
    const int* abc = kAbc[m_k];
    const std::int32_t id[4] = {w.v[m_k], w.v[abc[0]], w.v[abc[1]], w.v[abc[2]]};  // D, A, B, C
    Projected q[4];
    for (int j = 0; j < 4; ++j) q[j] = m_rays.at(id[j]);
    double e_d[4];
    int pattern = 0;
    for (int j = 1; j < 4; ++j) {
      e_d[j] = edge(q[0], q[j]);
      pattern |= static_cast<int>(edge_positive(e_d[j], q[0], id[0], q[j], id[j])) << (j - 1);
    }
    const int x = kExitX[pattern], y = x == 3 ? 1 : x + 1;
    m_next = w.next[abc[5 - x - y]];
    if (m_next >= 0) __builtin_prefetch(&m_in.tets[static_cast<std::size_t>(m_next >> 2)]);
    const double w3[3] = {std::max(0.0, edge(q[x], q[y])), std::max(0.0, -e_d[y]),
                          std::max(0.0, e_d[x])};
    const std::int32_t face[3] = {id[0], id[x], id[y]};
    const Projected face_q[3] = {q[0], q[x], q[y]};
    m_out = cross_face(m_rays, face, face_q, w3, m_enter);
    return true;
  }

  const Trace& trace() const { return m_tr; }
  bool grazed() const { return m_grazed; }

private:
  // An edge value; snapped to 0 within kSnap of its size when retrying (symmetric in a and b, so
  // every tet of the edge still sees the same value).
  double edge(const Projected& a, const Projected& b) const {
    const double e = edge_value(a, b);
    return Rays::kSnaps && std::fabs(e) <= noise(a, b) ? 0.0 : e;
  }
  static double noise(const Projected& a, const Projected& b) {
    return kSnap * ((a.x * a.x + a.y * a.y) + (b.x * b.x + b.y * b.y));  // grouped: exactly symmetric
  }

  // The start: whether the ray leaves through the face opposite v (outward order), i.e. all its
  // outward edges have positive values; sets the crossing.
  bool leaves_through(const std::int32_t face[3]) {
    Projected q[3];
    for (int j = 0; j < 3; ++j) q[j] = m_rays.at(face[j]);
    double e[3];
    bool positive = true;
    for (int j = 0; j < 3; ++j) {
      const int a = (j + 1) % 3, b = (j + 2) % 3;  // e(b, c) weighs a, and cyclically
      e[j] = edge(q[a], q[b]);
      if (edge_positive(e[j], q[a], face[a], q[b], face[b])) continue;
      positive = false;
      // Clearly outside this edge: neither the start nor touched on its rim. Most faces of the
      // star end here, at their first or second edge.
      if (e[j] < -noise(q[a], q[b])) return false;
    }
    if (!positive) {
      // Touched on its rim (every edge at least -noise), up to rounding noise: the ray runs
      // along the boundary.
      m_grazed = true;
      return false;
    }
    const double w3[3] = {std::max(0.0, e[0]), std::max(0.0, e[1]), std::max(0.0, e[2])};
    m_out = cross_face(m_rays, face, q, w3, Crossing{{m_v, m_v, m_v}, {1, 0, 0}, 0.0, m_rays.scalar(m_v)});
    return true;
  }

  void keep(const Crossing& c) {
    if (m_record)
      m_record->push_back({{c.id[0], c.id[1], c.id[2]},
                           {static_cast<float>(c.mu[0]), static_cast<float>(c.mu[1]), static_cast<float>(c.mu[2])},
                           static_cast<float>(c.t)});
  }

  // The departure point lies in the current tet: between the two crossings, its weights
  // interpolated likewise.
  void finish_inside() {
    const WalkTet& w = m_in.tets[static_cast<std::size_t>(m_slot)];
    const double f = m_out.t > m_enter.t ? (m_length - m_enter.t) / (m_out.t - m_enter.t) : 0.0;
    double weight[4] = {0, 0, 0, 0}, sum = 0;
    for (int j = 0; j < 4; ++j) {
      for (int c = 0; c < 3; ++c) {
        if (m_enter.id[c] == w.v[j]) weight[j] += (1 - f) * m_enter.mu[c];
        if (m_out.id[c] == w.v[j]) weight[j] += f * m_out.mu[c];
      }
      weight[j] = std::max(0.0, weight[j]);
      sum += weight[j];
    }
    for (int j = 0; j < 4; ++j) m_tr.weights[j] = static_cast<float>(sum > 0 ? weight[j] / sum : 0.25);
    const double s_end = m_enter.s + f * (m_out.s - m_enter.s);
    m_tr.depth += m_in.table.integral(m_enter.s, s_end, m_length - m_enter.t, &m_piece_hint);
    m_tr.kind = Trace::Kind::inside;
    m_tr.tet = m_slot;
    m_tr.end = m_length;
  }

  // The search among the star's faces begins: its offsets are fetched.
  void search_star() {
    __builtin_prefetch(&m_in.star_offsets[static_cast<std::size_t>(m_v)]);
    m_rays.prefetch(m_v);
    m_phase = Phase::offsets;
  }

  // offsets -> star -> scan (a start to search for), cached (a known one) or hinted (tried, then
  // searched for if it is not the start) -> enter, then peek -> step for every tet.
  enum class Phase { offsets, star, scan, cached, hinted, enter, peek, step };

  const WalkInput& m_in;
  Rays m_rays;
  std::int32_t m_v;
  double m_length;
  std::vector<WalkCrossing>* m_record;
  Trace m_tr;
  bool m_grazed = false;
  std::int32_t m_slot = -1, m_next = -1;
  int m_k = -1, m_piece_hint = -1, m_moves = 0;
  Phase m_phase = Phase::offsets;
  std::int32_t* m_cache = nullptr;
  std::int64_t m_star_begin = 0, m_star_end = 0;
  Crossing m_enter{}, m_out{};  // the segment in the current tet runs from m_enter to m_out
};

// A walk that could not start only by the tie rule or by rounding noise (a ray from a boundary
// vertex along the boundary, common on axis-aligned meshes and lights) is retried with the noise
// snapped to 0 and the tie rule's displacement turned by 0 to 3 quarters; the first that starts
// is kept (true): one of them pushes a ray along a boundary face, or along a convex edge of 90
// degrees or more, into the mesh, as the closed mesh holds it. (A ray that meets the boundary
// later, say along a hole's wall, leaves where the rule says and continues in level 0, as the
// light does across the hole.) Retried walks are not cached as starts.
template <class Rays>
bool walk_turned(const WalkInput& in, const Rays& rays, std::int32_t v, double length,
                 std::vector<WalkCrossing>* record, Trace& out) {
  for (int quarter = 0; quarter <= 3; ++quarter) {
    if (record) record->clear();
    Walker<TurnedRays<Rays>> walker(in, TurnedRays<Rays>{rays, quarter}, v, length, record);
    if (!walker.start(nullptr)) continue;
    while (walker.step()) {
    }
    out = walker.trace();
    return true;
  }
  if (record) record->clear();
  return false;
}

// Walks in flight per thread in walk_batch.
constexpr int kInFlight = 8;

template <class Rays, class MakeRays>
void walk_interleaved(const WalkInput& in, WalkJob* jobs, std::size_t count, const MakeRays& make_rays) {
  std::optional<Walker<Rays>> walkers[kInFlight];
  std::size_t job_of[kInFlight] = {};
  std::size_t next_job = 0;
  // A walk over gives its job's result; one that could not start only by the tie rule is
  // retried (walk_turned) and, if a retry starts, gives that one's.
  auto finish = [&](WalkJob& job, const Walker<Rays>& w) {
    if (w.grazed()) {
      if (job.start) *job.start = -1;
      if (walk_turned(in, make_rays(job), job.v, job.length, job.record, job.trace)) return;
    }
    job.trace = w.trace();
  };
  // Starts the next job in slot k (a job over at once is finished here); false when none is left.
  auto launch = [&](int k) {
    while (next_job < count) {
      WalkJob& job = jobs[next_job++];
      walkers[k].emplace(in, make_rays(job), job.v, job.length, job.record);
      if (walkers[k]->begin(job.start)) {
        job_of[k] = static_cast<std::size_t>(&job - jobs);
        return true;
      }
      finish(job, *walkers[k]);
    }
    walkers[k].reset();
    return false;
  };
  int active = 0;
  for (int k = 0; k < kInFlight; ++k) active += launch(k) ? 1 : 0;
  while (active > 0)
    for (int k = 0; k < kInFlight; ++k) {
      if (!walkers[k] || walkers[k]->advance()) continue;
      finish(jobs[job_of[k]], *walkers[k]);
      if (!launch(k)) --active;
    }
}

}  // namespace

void walk_batch(const WalkInput& in, WalkJob* jobs, std::size_t count) {
  if (in.parallel)
    walk_interleaved<ParallelRays>(in, jobs, count,
                                   [&](const WalkJob& j) { return ParallelRays{in.parallel, in.parallel[j.v]}; });
  else
    walk_interleaved<ConvergingRays>(in, jobs, count, [&](const WalkJob& j) {
      return ConvergingRays{detail::RayFrame(j.x, j.d), in.points, in.scalars};
    });
}

void project_parallel(const TetMesh& mesh, const Vec3d& towards, const std::vector<float>& scalars,
                      std::vector<ParallelPoint>& out) {
  // Projected about the mesh's centre: walks use differences of these, which then keep the mesh's
  // own relative precision wherever it sits.
  const detail::RayFrame frame(mesh.frame.center, towards);
  out.resize(mesh.points.size());
  parallel_for(out.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p) {
      const Projected q = frame.project(mesh.points[p]);
      out[p] = {q.x, q.y, q.depth, scalars[p]};
    }
  });
}

void hint_plane(const std::vector<ParallelPoint>& points, std::vector<float>& xy) {
  xy.resize(2 * points.size());
  if (points.empty()) return;
  const double x0 = points[0].x, y0 = points[0].y;
  parallel_for(points.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p) {
      xy[2 * p] = static_cast<float>(points[p].x - x0);
      xy[2 * p + 1] = static_cast<float>(points[p].y - y0);
    }
  });
}

void hint_parallel_starts(const std::vector<detail::WalkTet>& tets, const std::vector<float>& xy, std::size_t first,
                          std::size_t last, std::vector<std::int32_t>& start) {
  parallel_for(last - first, 1 << 13, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = first + b; t < first + e; ++t) {
      const WalkTet& w = tets[t];
      // The areas of the three faces through point 0 from its edges to the others
      // (kFaceVertices: face 1 is (0, 3, 2), face 2 (0, 1, 3), face 3 (0, 2, 1)); face 0's is
      // minus their sum, as the projected areas of a closed surface sum to zero.
      const std::size_t p0 = 2 * static_cast<std::size_t>(w.v[0]);
      float ex[4], ey[4];
      for (int j = 1; j < 4; ++j) {
        const std::size_t pj = 2 * static_cast<std::size_t>(w.v[j]);
        ex[j] = xy[pj] - xy[p0];
        ey[j] = xy[pj + 1] - xy[p0 + 1];
      }
      const float a1 = ex[3] * ey[2] - ey[3] * ex[2];
      const float a2 = ex[1] * ey[3] - ey[1] * ex[3];
      const float a3 = ex[2] * ey[1] - ey[2] * ex[1];
      // Exactly one face towards the light and three away from it: either faces 1 to 3 all away
      // (face 0 then faces the light), or two of them away and the third towards the light by
      // more than they are away (so face 0 is away). Counted without branches: which case holds
      // is a coin toss per tet.
      const int away = (a1 < 0) + (a2 < 0) + (a3 < 0);
      if (!(away == 3 || (away == 2 && a1 + a2 + a3 > 0))) continue;
      const int k = away == 3 ? 0 : (a1 >= 0) + 2 * (a2 >= 0) + 3 * (a3 >= 0);
      // Only a tie gives one vertex two such tets, and then any of them is a fair hint; the
      // stores are atomic so that the race is harmless. What other tets store here are hints
      // too, so the test of what may be replaced does not depend on them.
      std::atomic_ref<std::int32_t> slot(start[static_cast<std::size_t>(w.v[k])]);
      const std::int32_t now = slot.load(std::memory_order_relaxed);
      if (now == -1 || now <= kFirstHint)
        slot.store(kFirstHint - (static_cast<std::int32_t>(t) << 2 | k), std::memory_order_relaxed);
    }
  });
}

Trace walk_to_light(const WalkInput& in, std::int32_t v, const Vec3d& x, const Vec3d& d, double length,
                    std::int32_t* start, std::vector<WalkCrossing>* record) {
  WalkJob job{v, x, d, length, start, record, {}};
  walk_batch(in, &job, 1);
  return job.trace;
}

}  // namespace penumbra::render::lighting
