// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level1_walk.h -- the walk from a vertex towards the light through the tets
#pragma once
#include <cstdint>
#include <vector>

#include "ray_frame.h"
#include "walk_mesh.h"
#include "extinction_table.h"
#include "level1_mesh.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::render::lighting {

/// A point seen along a directional light: coordinates in the plane across the light, depth
/// towards the light, and its scalar; one 32-byte record per walk step.
struct ParallelPoint {
  double x, y, depth;
  float s;
};

/// Every point projected for a directional light towards unit direction `towards` (the frame of
/// detail::RayFrame, so the walk's edge signs follow ray_frame.h's rules).
void project_parallel(const TetMesh& mesh, const Vec3d& towards, const std::vector<float>& scalars,
                      std::vector<ParallelPoint>& out);

/// A point where a recorded walk crosses a face: the face's points and their weights there, and
/// its ray parameter. (The walk's start, at its vertex with ray parameter 0, is not recorded.) The scalar there is the
/// weighted mean of the points' scalars whatever the field, so a new field's optical depth along
/// a recorded walk needs no per-tet records.
struct WalkCrossing {
  std::int32_t id[3];
  float mu[3];
  float t;
};

/// Result of walking the straight segment from a vertex towards the light.
struct Trace {
  enum class Kind { inside, left_mesh, lost } kind = Kind::lost;
  std::int32_t tet = -1;  ///< walk record holding the end (inside) or the last one walked
  double end = 0;         ///< ray parameter of the departure point, or where the walk left the mesh
  double depth = 0;       ///< integral of tau over the walked part (exact)
  float weights[4] = {0, 0, 0, 0};  ///< inside: the end's barycentric weights in `tet` (convex)
};

/// What the walk reads: the tets as walk records with each point's incident records, the
/// extinction table, and the rays (one of the two).
struct WalkInput {
  const std::vector<detail::WalkTet>& tets;
  const std::vector<std::int64_t>& star_offsets;  ///< point p's records: star[star_offsets[p] ..]
  const std::vector<StarFace>& star;
  const ExtinctionTable& table;
  const ParallelPoint* parallel = nullptr;  ///< a directional light's projections, else
  const Vec3d* points = nullptr;            ///< the mesh points and
  const float* scalars = nullptr;           ///< their scalars (rays converging on a point light)
};

/// Walks from point v (at x) along unit direction d (towards the light) for `length`.
///
/// The walk is the renderer's (cpu_ray_caster.cpp): each step leaves the tet through the face
/// whose edges the ray passes on the inside, decided by the signs of 2D cross products in the
/// plane across the ray, each edge's value exactly the negative of its reverse's and exact zeros
/// broken by one consistent perturbation of the ray (ray_frame.h). Through vertices, along edges
/// and in face planes it therefore walks as a nearby generic ray would, never losing or doubling
/// a tet. The start is the tet of v's star whose face opposite v the ray leaves through (the
/// perturbed ray misses v, so exactly one such face lies ahead of an interior vertex; none: the
/// ray leaves the mesh at v). A walk from a boundary vertex that cannot start only by the tie
/// rule or by rounding noise (a ray along the boundary) is retried with the noise snapped to 0
/// and the rule's displacement turned, so that it runs inside the closed mesh. Depths and scalars
/// at each crossing are interpolated over the crossed face, so the optical depth of each segment
/// is integrated exactly.
/// `start`, when given, caches the start for this vertex and direction (-1: unknown, -2: the ray
/// leaves the mesh at v, >= 0: record << 2 | local index; <= kFirstHint: a hint, kFirstHint - the
/// start for another direction, tested before the search; hint_start makes one). `record`, when
/// given, receives every face the walk crosses (the end inside a tet is given by `weights`).
Trace walk_to_light(const WalkInput& in, std::int32_t v, const Vec3d& x, const Vec3d& d, double length,
                    std::int32_t* start = nullptr, std::vector<WalkCrossing>* record = nullptr);

/// Start cache values at or below this are hints (see walk_to_light).
inline constexpr std::int32_t kFirstHint = -3;

/// A start cache value turned into a hint when the direction changes (a light moved a little
/// mostly keeps each vertex's start tet; testing it first skips the search through the star).
inline std::int32_t hint_start(std::int32_t start) {
  return start >= 0 ? kFirstHint - start : start <= kFirstHint ? start : -1;
}

/// A directional light's starts, made hints (see walk_to_light) by a sweep over the tets instead
/// of a search through each vertex's star. With outward faces, the ray from a vertex runs into a
/// tet and out through the face opposite it exactly when that face is the only one of the tet
/// facing the light: its area projected across the light is the sum of the three edge values
/// walk_to_light tests there, and the other three faces' areas are those values negated. A tet
/// with exactly one face of positive area and three of negative area therefore names the start
/// of the vertex opposite that face, and each face is tested once per tet instead of once per
/// star it lies in (four). Ties (a zero area: rays in a face's plane) are left to the search; a
/// hint that rounding got wrong fails walk_to_light's test and is searched for, so the walks'
/// results do not change.
///
/// The points across the light as the sweep reads them: two floats per point relative to the
/// first, 8 bytes instead of 32, so that its gathers mostly hit the core's own cache.
void hint_plane(const std::vector<ParallelPoint>& points, std::vector<float>& xy);
/// The sweep over walk records [first, last): hints for the vertices whose start is unknown
/// (-1) or a hint; a cached start or -2 stays.
void hint_parallel_starts(const std::vector<detail::WalkTet>& tets, const std::vector<float>& xy, std::size_t first,
                          std::size_t last, std::vector<std::int32_t>& start);

/// One walk of a batch: walk_to_light's arguments and, after walk_batch, its result.
struct WalkJob {
  std::int32_t v;
  Vec3d x, d;
  double length;
  std::int32_t* start;
  std::vector<WalkCrossing>* record;
  Trace trace;
};

/// walk_to_light for every job, with several walks in flight per call: a walk step waits on
/// memory (the next tet, its new point), so the steps of different walks are interleaved and
/// their loads overlap. Every job's result equals walk_to_light's.
void walk_batch(const WalkInput& in, WalkJob* jobs, std::size_t count);

}  // namespace penumbra::render::lighting
