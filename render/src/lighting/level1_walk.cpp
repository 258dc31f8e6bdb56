// render/src/lighting/level1_walk.cpp -- the level-1 walk by edge signs in the plane across the ray
#include "level1_walk.h"

#include <algorithm>
#include <cmath>

#include "penumbra/core/thread_pool.h"

namespace penumbra::render::lighting {
namespace {

using detail::edge_positive;
using detail::edge_value;
using detail::kAbc;
using detail::kExitX;
using detail::kFaceVertices;
using detail::Projected;
using detail::WalkTet;

// A walk of one step crosses about step / edge tets; this cap only stops a walk that cycles in
// a degenerate configuration (it then falls back to level 0 and is counted).
constexpr int kMaxMoves = 200000;

// Rays parallel to a directional light: projections shared by every walk of the light, taken
// relative to the walk's own start.
struct ParallelRays {
  const ParallelPoint* points;
  ParallelPoint origin;
  Projected at(std::int32_t id) const {
    const ParallelPoint& p = points[id];
    return {p.x - origin.x, p.y - origin.y, p.depth - origin.depth};
  }
  double scalar(std::int32_t id) const { return points[id].s; }
};

// Rays converging on a point light: each walk projects the points it meets into its own frame.
struct ConvergingRays {
  detail::RayFrame frame;
  const Vec3d* points;
  const float* scalars;
  Projected at(std::int32_t id) const { return frame.project(points[id]); }
  double scalar(std::int32_t id) const { return scalars[id]; }
};

// The rays turned by a quarter turn (1, 2 or 3) in the plane across them. The tie rule displaces
// every ray by (eps, eps^2) in its plane; turning the plane turns that displacement, so each
// quarter pushes a ray lying in the mesh boundary to another side of it (see walk_to_light).
template <class Rays>
struct TurnedRays {
  Rays rays;
  int quarter;
  Projected at(std::int32_t id) const {
    const Projected p = rays.at(id);
    if (quarter == 1) return {-p.y, p.x, p.depth};
    if (quarter == 2) return {-p.x, -p.y, p.depth};
    return {p.y, -p.x, p.depth};
  }
  double scalar(std::int32_t id) const { return rays.scalar(id); }
};

// Where the ray crosses a face: the face's points and their weights (summing to 1).
struct Crossing {
  std::int32_t id[3];
  double mu[3];
  double t, s;
};

// The crossing of the face with points a, b, c (projected qa, qb, qc) from unnormalised weights
// w (>= 0); with all weights 0 (the ray in the face's plane) it stays at `t_in`, `s_in`.
template <class Rays>
Crossing cross_face(const Rays& rays, const std::int32_t id[3], const Projected q[3], const double w[3], double t_in,
                    double s_in) {
  Crossing c{{id[0], id[1], id[2]}, {0, 0, 0}, t_in, s_in};
  const double sum = w[0] + w[1] + w[2];
  if (!(sum > 0)) return c;
  const double inv = 1.0 / sum;
  c.t = c.s = 0.0;
  for (int j = 0; j < 3; ++j) {
    c.mu[j] = w[j] * inv;
    c.t += c.mu[j] * q[j].depth;
    c.s += c.mu[j] * rays.scalar(id[j]);
  }
  c.t = std::max(c.t, t_in);
  return c;
}

// The walk for one set of rays. `grazed` is set when it cannot start only by the tie rule: the
// unperturbed ray touches a face of v's star opposite v on its rim, so it runs along the
// boundary of the closed mesh.
template <class Rays>
Trace walk(const WalkInput& in, const Rays& rays, std::int32_t v, double length, std::int32_t* start,
           std::vector<WalkSegment>* record, bool& grazed) {
  Trace tr;
  grazed = false;
  if (start && *start == -2) {
    tr.kind = Trace::Kind::left_mesh;
    return tr;
  }
  // The start: the record of v's star whose face opposite v the ray leaves through, i.e. whose
  // outward edges all have positive values.
  Crossing out{};
  auto leaves_through = [&](const std::int32_t face[3]) {
    Projected q[3];
    for (int j = 0; j < 3; ++j) {
      out.id[j] = face[j];
      q[j] = rays.at(face[j]);
    }
    double e[3];
    bool positive = true;
    for (int j = 0; j < 3; ++j) {
      const int a = (j + 1) % 3, b = (j + 2) % 3;  // e(b, c) weighs a, and cyclically
      e[j] = edge_value(q[a], out.id[a], q[b], out.id[b]);
      positive = positive && edge_positive(e[j], q[a], out.id[a], q[b], out.id[b]);
    }
    if (!positive) {
      grazed = grazed || (e[0] >= 0 && e[1] >= 0 && e[2] >= 0);
      return false;
    }
    const double w3[3] = {std::max(0.0, e[0]), std::max(0.0, e[1]), std::max(0.0, e[2])};
    out = cross_face(rays, out.id, q, w3, 0.0, rays.scalar(v));
    return true;
  };
  std::int32_t slot = -1;
  int k = -1;
  if (start && *start >= 0) {
    slot = *start >> 2;
    k = *start & 3;
    const WalkTet& w = in.tets[static_cast<std::size_t>(slot)];
    const std::int32_t face[3] = {w.v[kFaceVertices[k][0]], w.v[kFaceVertices[k][1]], w.v[kFaceVertices[k][2]]};
    (void)leaves_through(face);  // known to hold: only the crossing is wanted
    grazed = false;
  } else {
    const auto s_end = in.star_offsets[static_cast<std::size_t>(v) + 1];
    for (auto s = in.star_offsets[static_cast<std::size_t>(v)]; s < s_end; ++s) {
      const StarFace& f = in.star[static_cast<std::size_t>(s)];
      if (leaves_through(f.v)) {
        slot = f.record >> 2;
        k = f.record & 3;
        break;
      }
    }
    if (slot >= 0) grazed = false;
    if (start) *start = slot < 0 ? -2 : (slot << 2 | k);
    if (slot < 0) {
      tr.kind = Trace::Kind::left_mesh;
      return tr;
    }
  }

  // The segment inside the current tet runs from `enter` to `out`; v itself enters the first.
  Crossing enter{{v, v, v}, {1, 0, 0}, 0.0, rays.scalar(v)};
  int piece_hint = -1;
  std::int32_t next = in.tets[static_cast<std::size_t>(slot)].next[k];
  for (int move = 0; move < kMaxMoves; ++move) {
    if (out.t >= length) {
      // The departure point: between the two crossings, weights interpolated likewise.
      const WalkTet& w = in.tets[static_cast<std::size_t>(slot)];
      const double f = out.t > enter.t ? (length - enter.t) / (out.t - enter.t) : 0.0;
      double weight[4] = {0, 0, 0, 0}, sum = 0;
      for (int j = 0; j < 4; ++j) {
        for (int c = 0; c < 3; ++c) {
          if (enter.id[c] == w.v[j]) weight[j] += (1 - f) * enter.mu[c];
          if (out.id[c] == w.v[j]) weight[j] += f * out.mu[c];
        }
        weight[j] = std::max(0.0, weight[j]);
        sum += weight[j];
      }
      for (int j = 0; j < 4; ++j) tr.weights[j] = static_cast<float>(sum > 0 ? weight[j] / sum : 0.25);
      const double s_end = enter.s + f * (out.s - enter.s);
      tr.depth += in.table.integral(enter.s, s_end, length - enter.t, &piece_hint);
      if (record) record->push_back({slot, static_cast<float>(enter.t), static_cast<float>(length)});
      tr.kind = Trace::Kind::inside;
      tr.tet = slot;
      tr.end = length;
      return tr;
    }
    tr.depth += in.table.integral(enter.s, out.s, out.t - enter.t, &piece_hint);
    if (record) record->push_back({slot, static_cast<float>(enter.t), static_cast<float>(out.t)});
    if (next < 0) {
      tr.kind = Trace::Kind::left_mesh;
      tr.tet = slot;
      tr.end = out.t;
      return tr;
    }
    // The next tet, entered through face k: leave through the face (D, X, Y) picked by the signs
    // of the edges from D, the vertex opposite the entry.
    slot = next >> 2;
    k = next & 3;
    enter = out;
    const WalkTet& w = in.tets[static_cast<std::size_t>(slot)];
    const int* abc = kAbc[k];
    const std::int32_t id[4] = {w.v[k], w.v[abc[0]], w.v[abc[1]], w.v[abc[2]]};  // D, A, B, C
    Projected q[4];
    for (int j = 0; j < 4; ++j) q[j] = rays.at(id[j]);
    double e_d[4];
    int pattern = 0;
    for (int j = 1; j < 4; ++j) {
      e_d[j] = edge_value(q[0], id[0], q[j], id[j]);
      pattern |= static_cast<int>(edge_positive(e_d[j], q[0], id[0], q[j], id[j])) << (j - 1);
    }
    const int x = kExitX[pattern], y = x == 3 ? 1 : x + 1;
    next = w.next[abc[5 - x - y]];
    if (next >= 0) __builtin_prefetch(&in.tets[static_cast<std::size_t>(next >> 2)]);
    const double w3[3] = {std::max(0.0, edge_value(q[x], id[x], q[y], id[y])), std::max(0.0, -e_d[y]),
                          std::max(0.0, e_d[x])};
    const std::int32_t face[3] = {id[0], id[x], id[y]};
    const Projected face_q[3] = {q[0], q[x], q[y]};
    out = cross_face(rays, face, face_q, w3, enter.t, enter.s);
  }
  tr.kind = Trace::Kind::lost;
  tr.tet = slot;
  tr.end = length;
  return tr;
}

// The walk as the tie rule has it; when that cannot start only by the rule (a ray from a
// boundary vertex along the boundary, common on axis-aligned meshes and lights), the other three
// quarter turns of the displacement are tried, and the first that starts is kept: one of them
// pushes a ray along a boundary face, or along a convex edge of 90 degrees or more, into the mesh,
// as the closed mesh holds it. (A ray that meets the boundary later, say along a hole's wall,
// leaves where the rule says and continues in level 0, as the light does across the hole.)
// Retried walks are not cached as starts.
template <class Rays>
Trace walk_any_side(const WalkInput& in, const Rays& rays, std::int32_t v, double length, std::int32_t* start,
                    std::vector<WalkSegment>* record) {
  bool grazed = false;
  const Trace first = walk(in, rays, v, length, start, record, grazed);
  if (!grazed) return first;
  if (start) *start = -1;
  for (int quarter = 1; quarter <= 3; ++quarter) {
    if (record) record->clear();
    const Trace t = walk(in, TurnedRays<Rays>{rays, quarter}, v, length, nullptr, record, grazed);
    if (t.tet >= 0) return t;
  }
  if (record) record->clear();
  return first;
}

}  // namespace

void project_parallel(const TetMesh& mesh, const Vec3d& towards, const std::vector<float>& scalars,
                      std::vector<ParallelPoint>& out) {
  const detail::RayFrame frame({0, 0, 0}, towards);
  out.resize(mesh.points.size());
  parallel_for(out.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p) {
      const Projected q = frame.project(mesh.points[p]);
      out[p] = {q.x, q.y, q.depth, scalars[p]};
    }
  });
}

Trace walk_to_light(const WalkInput& in, std::int32_t v, const Vec3d& x, const Vec3d& d, double length,
                    std::int32_t* start, std::vector<WalkSegment>* record) {
  if (in.parallel) return walk_any_side(in, ParallelRays{in.parallel, in.parallel[v]}, v, length, start, record);
  return walk_any_side(in, ConvergingRays{detail::RayFrame(x, d), in.points, in.scalars}, v, length, start, record);
}

}  // namespace penumbra::render::lighting
