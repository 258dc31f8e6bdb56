// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level1_solve.h -- semi-Lagrangian steps (eq. 6-8) on the tet mesh
#pragma once
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <vector>

#include "crossing_arena.h"
#include "level0_grid.h"
#include "level1_mesh.h"
#include "level1_walk.h"
#include "penumbra/render/light_volume.h"

namespace penumbra::render::lighting {

/// Makes v's storage hold n elements, written once so that its pages are in memory, and leaves v
/// empty: a later resize or assign up to n then costs neither an allocation nor a page fault.
template <class T>
void reserve_touched(std::vector<T>& v, std::size_t n) {
  v.assign(n, T{});
  v.clear();
}

/// Everything one semi-Lagrangian pass reads.
struct Level1Context {
  const TetMesh& mesh;
  const Level1Topology& topology;
  const Level1Field& field;
  const Level0Grid& grid;
  const std::vector<Bounds>& occluders;
  double sigma_a;
  double step;           ///< h = c dt, world units
  bool adaptive = true;  ///< each vertex steps at least twice its longest edge (see level1_step)
  bool record_walks = true;  ///< keep each vertex's walk (PassState::walks) for the next field
  /// The step of vertex v: h, or with `adaptive` at least twice v's longest edge, so that its
  /// departure tet lies wholly upstream and one ordered pass carries the light across coarse
  /// cells too (with h far below a cell, each pass would move the light by h only). The steady
  /// state does not depend on the step, so this changes convergence speed, not the answer
  /// (beyond interpolation error, which longer steps reduce).
  double step_of(std::size_t v) const {
    return adaptive ? std::max(step, 2.0 * static_cast<double>(topology.longest_edge[v])) : step;
  }
};

/// Length of the ray from x towards the light that lies inside `box` (the mesh bounds).
double box_path_length(const Bounds& box, const Vec3d& x, const Light& light);

/// rho at a departure point from the corners of its tet, weights w (convex). Attenuated light is
/// exp(-optical depth D), and D is far smoother than rho. The departure point gets
///     D_d = m path_d,  m = (sum w_k D_k) / (sum w_k path_k),
/// path the length of the ray inside the mesh bounds (box_path_length): the interpolated depth,
/// rescaled by how much longer the departure point's own path is than the interpolated one. Where
/// the path is linear across the tet this is plain interpolation of D, exact behind and inside a
/// thin absorber; where it has a kink (the ray's entry face changes inside the tet; a point
/// light's cone tip) the rescaling follows it, so a homogeneous medium is exact for directional
/// and point lights at any step length, where linear interpolation of rho errs at every step.
/// m is a weighted mean of the corners' mean extinctions, >= 0, so the result is in [0, 1].
/// Across a shadow edge the depth changes steeply *across* the light, beyond what the model
/// D = m path explains; interpolating D there would let the dark side win and shadows grow by the
/// numerical blur, so rho is interpolated linearly instead when that unexplained change
/// perpendicular to the light (over the tet's longest edge) exceeds ln 16, blended from ln 4, and
/// next to an exactly dark corner (occluder, or light flushed to zero). Both forms are bounded
/// and do not oscillate. u is the light's direction of travel at the departure point.
/// Returns NaN when every corner lies on the inflow boundary (no path, nothing to interpolate)
/// but the departure point does not: the caller then walks on to the boundary.
double interpolate_light(const std::array<double, 4>& w, const double rho[4], const double path[4], double path_d,
                         const Vec3d corner[4], const Vec3d& u);

/// Change of `value` (linear over the tet with corners p) perpendicular to direction u:
/// |component of its gradient normal to u| times the tet's longest edge.
double transverse_change(const Vec3d p[4], const double value[4], const Vec3d& u);

/// Vertices grouped along the light by their key (directional: x . u; point: distance from the
/// light) into the slabs [k0 + g step / 2, k0 + (g + 1) step / 2), k0 the smallest key, empty
/// slabs left out: a departure point lies a full step upstream, so the tet holding it has its
/// vertices in earlier groups unless it is thicker than step / 2. Within a group, vertices keep
/// the order of their ids.
struct VertexOrder {
  std::vector<std::int32_t> vertices;
  std::vector<std::size_t> group_end;
  std::vector<std::int32_t> group_of;  ///< per point; -1 for points in no tet
  /// Per point: box_path_length from it towards the light (read at every departure tet's corners).
  std::vector<double> path_length;
  std::vector<double> key;  ///< order_vertices' scratch: each point's position along the light
  /// Allocates (and touches) the arrays for np points, the order staying empty.
  void reserve(std::size_t np) {
    reserve_touched(path_length, np);
    reserve_touched(key, np);
    reserve_touched(vertices, np);
    reserve_touched(group_of, np);
  }
};

/// A vertex's walk towards the light, kept while the light and the step stay. The faces crossed
/// (with the crossing points' weights and ray parameters) and the departure point's tet, weights
/// and path length depend on the geometry only, so a new field (the next in-situ time step)
/// re-integrates the extinction between the recorded crossings instead of walking again.
struct RecordedWalk {
  /// `count` crossings in the light's CrossingArena (PassState::crossings); a span of `capacity`
  /// is this walk's until the arena is reset, and a walk recorded again reuses it if it fits.
  WalkCrossing* crossings = nullptr;
  std::uint32_t count = 0, capacity = 0;
  std::int32_t tet = -1;  ///< Trace::tet
  float end = 0;          ///< Trace::end
  float weights[4] = {0, 0, 0, 0};  ///< Trace::weights
  double path = 0;        ///< box_path_length at the departure point
  std::uint8_t kind = 0;  ///< Trace::Kind
  bool valid = false, has_path = false;
};

/// What a pass remembers for the next: each vertex's departure corners and whether it read a
/// corner not yet updated in its pass (stale). Reset it (clear()) whenever the light, field or
/// step changes.
struct PassState {
  std::vector<std::int32_t> start_tet;  ///< per vertex, see walk_to_light; kept across clear()
  std::vector<RecordedWalk> walks;      ///< per vertex; kept across clear(), like start_tet
  CrossingArena crossings;              ///< the walks' crossings
  /// Per vertex, the corners of its departure tet (4 ids; -1: its value came from level 0 or the
  /// light): the passes after the first check them for changes in pass order, without loading
  /// the tets. Empty after clear(): the next pass is full.
  std::vector<std::array<std::int32_t, 4>> departure_corners;
  std::vector<std::uint8_t> stale, changed;
  /// The vertices whose value changed during the last call (so that only they are combined and
  /// copied out after it).
  std::vector<std::int32_t> changed_now;
  std::vector<float> next;
  std::vector<ParallelPoint> parallel;  ///< a directional light's projections, built per full pass
  /// A new directional light's start hints, made at the start of its full pass in slices of
  /// walk records [hint_next, hint_end) (hint_parallel_starts) from hint_xy (hint_plane).
  std::vector<float> hint_xy;
  std::size_t hint_next = 0, hint_end = 0;
  double hint_slice_ms = -1.0;  ///< the last slice's time (< 0: none yet); kept across clear()
  // A pass interrupted by its deadline resumes at next_group, vertex next_vertex of the order.
  bool in_pass = false, full = false;
  std::size_t next_group = 0, next_vertex = 0;
  double residual = 0.0;  ///< largest change of the pass so far / of the last finished pass
  /// Recent time per vertex of a batch (ms; < 0: none timed yet): a batch starts only if it is
  /// expected to end by the deadline. Kept across clear().
  double vertex_ms = -1.0;
  /// The set-up of the last full pass (ms; < 0: none yet): its arrays and a directional light's
  /// projections, which come before its first batch. Kept across clear().
  double full_setup_ms = -1.0;
  void clear() {
    departure_corners.clear();
    in_pass = false;
  }
  /// Sizes the per-vertex walk state for np vertices, the recorded walks only if `record`
  /// (their storage kept when already sized).
  void prepare_walks(std::size_t np, bool record) {
    if (start_tet.size() != np) start_tet.assign(np, -1);
    if (!record) {
      walks = {};
      crossings = {};
    } else if (walks.size() != np) {
      walks.assign(np, RecordedWalk{});
      crossings.reset();
    }
  }
  /// Allocates (and touches) the memory of a first pass over np vertices, the recorded walks'
  /// `crossings` included if `record`, while leaving the state as new: a light volume does this
  /// for its first light when it is built, so that the light's first frames do not spend their
  /// budget on page faults.
  void reserve(std::size_t np, bool record, std::size_t crossings) {
    prepare_walks(np, record);
    if (record) this->crossings.reserve(crossings);
    reserve_touched(departure_corners, np);
    reserve_touched(changed_now, np);
    reserve_touched(stale, np);
    reserve_touched(changed, np);
    reserve_touched(next, np);
    reserve_touched(parallel, np);
    reserve_touched(hint_xy, 2 * np);
  }
  /// Every recorded walk invalid (the light moved): their crossings' storage serves the next.
  void forget_walks() {
    for (RecordedWalk& w : walks) w = RecordedWalk{};
    crossings.reset();
  }
};
/// `reuse`: an earlier order whose arrays are filled anew (no new memory for a light that moved).
VertexOrder order_vertices(const TetMesh& mesh, const Level1Topology& topology, const Light& light, double step,
                           VertexOrder reuse = {});

/// Walk records per slice of a new light's start hints (hint_parallel_starts), the granularity
/// at which a time budget can stop them.
inline constexpr std::size_t kHintSlice = 1 << 16;

/// First estimates of a pass's timings (PassState::vertex_ms, full_setup_ms, hint_slice_ms) on
/// this mesh and machine, for a light whose passes have not run yet, so that its first pass
/// plans its batches from its first call (an untimed piece waits for a call of its own). Timed
/// on a light along -z through a unit medium: the projections of a full pass's set-up, one slice
/// of start hints, and walks from kLevel1Batch vertices spread over the mesh, run in parallel as
/// a pass runs them; each rounded up by half, for the walks of the rest of a vertex's update.
/// A pass's own timings replace them as it runs.
void prime_pass_timing(const Level1Context& ctx, PassState& state);

/// Vertices per batch of a pass: the granularity at which a time budget can stop it.
inline constexpr std::size_t kLevel1Batch = 2048;
/// The smallest batch a pass starts to use up the rest of a time budget.
inline constexpr std::size_t kLevel1MinBatch = 256;

/// One Gauss-Seidel pass of eq. 8 over the vertices in `order` (groups in order, the vertices
/// of a group in parallel, reading the values of earlier groups already updated):
///     rho(x) = rho(x_d) * exp(-sigma_a * integral of tau from x_d to x),  x_d = x - h u,
/// rho(x_d) interpolated in level 1 (interpolate_light), the level-0 value where the walk left
/// the mesh, 1 at the light. The first pass after a reset computes every vertex; later passes
/// only the stale ones and those whose departure corners changed in this pass (the others would
/// reproduce their value exactly). A new directional light's full pass begins with its start
/// hints (hint_parallel_starts) in slices. A pass stops between slices or batches of vertices
/// when not even kLevel1MinBatch vertices are expected to end by `deadline` (state.vertex_ms;
/// batches shrink to what fits; the call's first runs whatever the room, down to
/// kLevel1MinBatch) and resumes there on
/// the next call; returns true when the pass finished, its largest change then
/// in state.residual. `lost` counts walks that hit their move cap.
bool level1_pass(const Level1Context& ctx, const Light& light, const std::vector<float>& rho0,
                 const VertexOrder& order, std::vector<float>& rho1, PassState& state, std::atomic<std::size_t>& lost,
                 std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max());

}  // namespace penumbra::render::lighting
