// SPDX-License-Identifier: BSD-3-Clause
// render/src/cpu_ray_caster.cpp -- boundary entries by screen bins (or a BVH), tet walk by Plücker
// signs, several rays in flight, exact segment integration
#include "penumbra/render/cpu_ray_caster.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "bvh.h"
#include "penumbra/core/error.h"
#include "render_inputs.h"
#include "penumbra/core/thread_pool.h"
#include "ray_frame.h"
#include "ray_runs.h"
#include "screen_frame.h"
#include "shade_context.h"
#include "tet_order.h"
#include "tf_table.h"
#include "walk_geometry.h"
#include "walk_mesh.h"

namespace penumbra::render {
namespace {

using detail::Composite;
using detail::Modulation;
using detail::edge_sign;
using detail::edge_value;
using detail::Projected;
using detail::RayFrame;
using detail::RayGeometry;
using detail::ScreenBasis;
using detail::ScreenGeometry;
using detail::ScreenPoint;
using detail::TfTable;
using detail::BoundaryTriangle;
using detail::kFaceVertices;
using detail::ShadeContext;
using detail::WalkTet;

using detail::kAbc;
using detail::kExitX;

// A boundary face where the ray enters the mesh.
struct Entry {
  double t, s;
  std::int32_t tet, face;
  double light[3] = {1, 1, 1};  // L(x) at the entry point (shaded renders only)
};

struct WalkStats {
  double length = 0;
  int segments = 0;
  int entries = 0;
};

// A segment walked but not yet integrated: a ray walks up to kPendingSegments tets, then
// integrates them in one go. The walk is a chain of dependent loads and arithmetic (tet record,
// new point, edge signs, exit face, next tet) and the integration is independent arithmetic per
// segment; interleaved step by step, each step's integration fills the processor's window so
// that the next step's chain cannot start early, while apart the chains of several rays overlap
// (kRaysInFlight) and the integration runs at full width.
struct PendingSegment {
  double s0, s1, length;
  int p0, p1;  // transfer-function pieces of s0 and s1, -1 for NaN
};
constexpr int kPendingSegments = 16;

// One walk from a boundary entry, advanced a tet at a time by Impl::step, so that a tile can
// keep several rays walking at once.
struct WalkCursor {
  std::int32_t tet = 0;
  int k = 0;  // the face of `tet` the ray entered through
  double t_in = 0, s_in = 0;
  int p_in = -1;  // transfer-function piece of s_in, -1 for NaN
  double l_in[3] = {0, 0, 0};
  int zero_steps = 0;
  std::size_t steps = 0;
  double length_before = 0;
  // The entry face's points and projections, for geometries that reuse them (kReuseFace).
  std::int32_t face_id[3] = {-1, -1, -1};
  Projected face_q[3];
  // Unshaded walks: segments walked and not yet integrated; `opaque` once the ray is.
  int pending_count = 0;
  bool opaque = false;
  bool stuck = false;  // ended by too many zero-length steps: not counted as an entry
  PendingSegment pending[kPendingSegments];
};

// What every ray of a screen-space frame shares.
struct FrameContext {
  const Camera& camera;
  Camera::Frame camera_frame;
  const ScreenPoint* screen;
  ScreenBasis basis;
  const detail::ScreenBins& bins;
  int bin, bins_x;
  const TfTable& tf;
  const ShadeContext* shade;
  double stop_transmittance;
};

// Where a walk began and the ray's composite then: with the composite where it ended, the run
// it walked (RenderOptions::ray_runs).
struct RunStart {
  double depth = 0;
  Composite before;
};

using detail::PixelRuns;

// The run of a walk that began at `start` and left the mesh at `exit_depth` with `after`: what
// it alone adds, premultiplied (front to back, after = before + T_before x run).
void add_run(const RunStart& start, double exit_depth, const Composite& after, std::vector<RayRun>& runs) {
  if (!(exit_depth > start.depth)) return;  // a graze along the boundary
  const double t0 = start.before.transmittance;
  RayRun r;
  r.entry_depth = static_cast<float>(start.depth);
  r.exit_depth = static_cast<float>(exit_depth);
  if (t0 > 0) {
    for (int c = 0; c < 3; ++c) r.rgba[c] = static_cast<float>((after.rgb[c] - start.before.rgb[c]) / t0);
    r.rgba[3] = static_cast<float>(1.0 - after.transmittance / t0);
  }
  runs.push_back(r);
}

// One pixel's ray while it walks: its entries, the walk under way and its composite.
struct RayJob {
  int x = 0, y = 0;
  RayFrame frame;
  ScreenGeometry geo;
  std::vector<Entry> entries;
  std::size_t next_entry = 0;
  double done = 0;  // depth where the last walk left the mesh
  WalkCursor cursor;
  Composite acc;
  WalkStats stats;
  RunStart run;
};

// Rays a tile walks side by side. One walk step is a chain of dependent loads and arithmetic
// that the processor cannot overlap with the next step of the same ray; the steps of
// independent rays, interleaved, give it work to overlap (8 rays: about 12 % faster than one on
// a 1M-tet mesh; 16 gain nothing more).
constexpr int kRaysInFlight = 8;
constexpr int kPointLookahead = 2;

// A ray's composite as an image pixel: premultiplied colour and opacity.
void store_pixel(const Composite& acc, float* px) {
  for (int c = 0; c < 3; ++c) px[c] = static_cast<float>(acc.rgb[c]);
  px[3] = static_cast<float>(1.0 - acc.transmittance);
}

// Front to back. Usually one or two entries: insertion sort.
void sort_entries(std::vector<Entry>& out) {
  for (std::size_t i = 1; i < out.size(); ++i)
    for (std::size_t j = i; j > 0 && out[j].t < out[j - 1].t; --j) std::swap(out[j], out[j - 1]);
}

// A screen bin with more boundary faces than this is searched through the BVH instead: testing
// a face costs about 1/300 of a BVH search (about 45 against 15 000 instructions on a 1M-tet
// mesh, whose search also mispredicts many more branches).
constexpr std::int32_t kMaxBinFaces = 256;

constexpr int kMaxZeroLengthSteps = 1024;
// Relative to the mesh diagonal: stretches inside shorter than this are grazes, not entries.
constexpr double kGrazeLength = 1e-12;

// Composites the pending segments in order until the ray is opaque; true if it became opaque.
// Counts the segments composited (the ones past the point where the ray became opaque were
// walked for nothing and are not counted).
bool integrate_pending(const TfTable& tf, const PendingSegment* pending, int count, double stop_transmittance,
                       Composite& acc, WalkStats& stats) {
  for (int i = 0; i < count; ++i) {
    const PendingSegment& g = pending[i];
    if (tf.emits(g.p0, g.p1)) tf.integrate(g.s0, g.p0, g.s1, g.p1, g.length, acc);
    stats.length += g.length;
    ++stats.segments;
    if (acc.transmittance < stop_transmittance) return true;
  }
  return false;
}

}  // namespace

struct CpuRayCaster::Impl {
  std::shared_ptr<const TetMesh> mesh;
  // The walk numbers the points in Morton order of their positions, as it orders the tets, so
  // that the points a tile of rays reads lie close in memory whatever the mesh's numbering (a
  // shuffled numbering costs about 15 % of a frame on a 1M-tet mesh): walk point i is the mesh's
  // point point_ids[i], at points[i].
  std::vector<std::int32_t> point_ids;
  std::vector<Vec3d> points;
  std::vector<WalkTet> tets;
  std::vector<BoundaryTriangle> triangles;
  detail::Bvh bvh;
  double reentry_slack = 0;  // depth tolerance for re-entering at an exit (see trace_ray)

  explicit Impl(std::shared_ptr<const TetMesh> m);
  // The points in the walk's order, the boundary faces' BVH and the re-entry slack, from mesh's
  // positions (at construction, and after move_points).
  void place_points();
  // Geometry: RayGeometry or ScreenGeometry (walk_geometry.h). `f` is the ray itself, for the
  // BVH and the shading.
  template <class Geometry>
  void find_entries(const RayFrame& f, const Geometry& geo, const ShadeContext* shade,
                    std::vector<Entry>& out) const;
  // Starts `c` at `entry` (see WalkCursor).
  void begin_walk(const TfTable& tf, const Entry& entry, const WalkStats& stats, WalkCursor& c) const;
  // Starts `c` at the next of `entries` from `next` that is not behind `done`, the depth where
  // the ray's last walk left the mesh; false when none is left.
  bool begin_next_walk(const TfTable& tf, const std::vector<Entry>& entries, std::size_t& next, double done,
                       const WalkStats& stats, WalkCursor& c) const;
  // Walks `c` through one tet. Returns false when its walk ended: at the boundary exit, when the
  // ray became opaque or when the walk was cut short. kShaded: the emitted colour is modulated
  // by `shade` (null otherwise); a separate instantiation keeps the unshaded walk free of it.
  template <bool kShaded, class Geometry>
  bool step(const RayFrame& f, const Geometry& geo, const TfTable& tf, const ShadeContext* shade,
            double stop_transmittance, WalkCursor& c, Composite& acc, WalkStats& stats) const;
  // Counts an ended walk as an entry unless it only grazed the boundary.
  void end_walk(const TfTable& tf, double stop_transmittance, WalkCursor& c, Composite& acc, WalkStats& stats) const;
  // Composites one ray: every entry, front to back, until the ray is opaque.
  // `runs` (optional) receives the walks as runs.
  template <class Geometry>
  void trace_ray(const RayFrame& f, const Geometry& geo, const TfTable& tf,
                 const ShadeContext* shade, double stop_transmittance, std::vector<Entry>& entries, Composite& acc,
                 WalkStats& stats, std::vector<RayRun>* runs = nullptr) const;
  // Renders the pixels of one tile in screen space, keeping kRaysInFlight rays walking side by
  // side (see RayJob); `runs` (optional) receives each pixel's runs.
  template <bool kShaded>
  void render_tile(const FrameContext& fc, int x0, int y0, int x1, int y1, RayJob* jobs, Image& image,
                   PixelRuns* runs) const;
  // Renders a frame into `image` (sized), and each pixel's runs into `runs` when given.
  void render_frame(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
                    const RenderOptions& options, Image& image, PixelRuns* runs, detail::RunsBudget* budget) const;
};

CpuRayCaster::Impl::Impl(std::shared_ptr<const TetMesh> m) : mesh(std::move(m)) {
  require(mesh != nullptr, "CpuRayCaster: mesh is null; expected a prepared TetMesh");
  const TetMesh& tm = *mesh;
  require(tm.neighbors.size() == tm.tets.size(), "CpuRayCaster: mesh has " + std::to_string(tm.neighbors.size()) +
                                                     " neighbour entries for " + std::to_string(tm.tets.size()) +
                                                     " tets; expected a mesh from prepare_tet_mesh");
  // Walk records in Morton order of the tet centroids, so that a tile of rays walking through a
  // region touches few cache lines whatever the input ordering.
  const std::vector<std::int32_t> order = detail::morton_order(tm);
  std::vector<std::int32_t> rank(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) rank[static_cast<std::size_t>(order[i])] = static_cast<std::int32_t>(i);
  point_ids = detail::morton_point_order(tm);
  std::vector<std::int32_t> point_rank(point_ids.size());
  for (std::size_t i = 0; i < point_ids.size(); ++i) point_rank[static_cast<std::size_t>(point_ids[i])] = static_cast<std::int32_t>(i);
  tets = detail::walk_tets(tm, order);
  for (WalkTet& w : tets)
    for (std::int32_t& v : w.v) v = point_rank[static_cast<std::size_t>(v)];
  triangles.reserve(tm.boundary.size());
  for (const auto& bf : tm.boundary) {
    const auto& tv = tm.tets[static_cast<std::size_t>(bf.tet)];
    BoundaryTriangle tri{};
    for (int j = 0; j < 3; ++j) tri.v[j] = point_rank[static_cast<std::size_t>(tv[kFaceVertices[bf.face][j]])];
    tri.tet = rank[static_cast<std::size_t>(bf.tet)];
    tri.face = bf.face;
    triangles.push_back(tri);
  }
  place_points();
}

void CpuRayCaster::Impl::place_points() {
  const TetMesh& tm = *mesh;
  points.resize(point_ids.size());
  parallel_for(points.size(), 1 << 15, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) points[i] = tm.points[static_cast<std::size_t>(point_ids[i])];
  });
  std::vector<Bounds> boxes(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i)
    for (const std::int32_t v : triangles[i].v) boxes[i].extend(points[static_cast<std::size_t>(v)]);
  bvh = detail::Bvh(boxes, 1e-9 * std::max(tm.bounds.diagonal(), 1e-300), 4);
  reentry_slack = 1e-9 * tm.bounds.diagonal();
}

template <class Geometry>
void CpuRayCaster::Impl::find_entries(const RayFrame& f, const Geometry& geo, const ShadeContext* shade,
                                      std::vector<Entry>& out) const {
  out.clear();
  auto test_face = [&](std::int32_t i) {
    const BoundaryTriangle& tri = triangles[static_cast<std::size_t>(i)];
    Projected q[3];
    for (int j = 0; j < 3; ++j) q[j] = geo.at(tri.v[j]);
    // e[j]: edge v[j] -> v[j+1]. The ray enters through an outward face when it sees the face
    // clockwise: every edge negative. Most listed faces miss the ray, so all three values are
    // tested in one branch (three would each be mispredicted often), ties only when one is 0.
    const double e[3] = {edge_value(q[0], q[1]), edge_value(q[1], q[2]), edge_value(q[2], q[0])};
    if (!((e[0] <= 0) & (e[1] <= 0) & (e[2] <= 0))) return;
    if ((e[0] == 0) | (e[1] == 0) | (e[2] == 0)) [[unlikely]] {
      for (int j = 0; j < 3; ++j) {
        const int n = j == 2 ? 0 : j + 1;
        if (edge_sign(e[j], q[j], tri.v[j], q[n], tri.v[n]) >= 0) return;
      }
    }
    // Barycentric weight of a vertex: the opposite edge's value.
    const double w[3] = {std::max(0.0, -e[1]), std::max(0.0, -e[2]), std::max(0.0, -e[0])};
    if (!(w[0] + w[1] + w[2] > 0)) return;
    const detail::FacePoint fp = geo.interpolate(w, q[0], q[1], q[2]);
    Entry en;
    en.t = fp.t;
    en.s = fp.mu[0] * geo.scalar(tri.v[0]) + fp.mu[1] * geo.scalar(tri.v[1]) + fp.mu[2] * geo.scalar(tri.v[2]);
    en.tet = tri.tet;
    en.face = tri.face;
    if (shade != nullptr) shade->face_light(tri.v, fp.mu, f.origin + f.d * en.t, en.light);
    out.push_back(en);
  };
  if constexpr (Geometry::kBinnedFaces) {
    if (geo.faces_begin != nullptr) {
      for (const std::int32_t* i = geo.faces_begin; i != geo.faces_end; ++i) test_face(*i);
      return sort_entries(out);
    }
  }
  // Entries behind the origin matter only when the origin may be inside the mesh (the walk from
  // such an entry reaches t = 0 inside); from outside the bounds every stretch inside the mesh
  // lies wholly in front of or behind the origin.
  constexpr double inf = std::numeric_limits<double>::infinity();
  const Bounds& b = mesh->bounds;
  const double pad = 1e-9 * b.diagonal();
  const Vec3d& o = f.origin;
  const bool outside = o.x < b.lo.x - pad || o.y < b.lo.y - pad || o.z < b.lo.z - pad || o.x > b.hi.x + pad ||
                       o.y > b.hi.y + pad || o.z > b.hi.z + pad;
  bvh.for_each_on_line(f.origin, f.d, outside ? 0.0 : -inf, inf, test_face);
  sort_entries(out);
}

void CpuRayCaster::Impl::begin_walk(const TfTable& tf, const Entry& entry, const WalkStats& stats,
                                    WalkCursor& c) const {
  c.tet = entry.tet;
  c.k = entry.face;
  c.t_in = entry.t;
  c.s_in = entry.s;
  c.p_in = tf.piece_or_nan(entry.s);
  for (int i = 0; i < 3; ++i) c.l_in[i] = entry.light[i];
  c.zero_steps = 0;
  c.steps = 0;
  c.length_before = stats.length;
  c.face_id[0] = c.face_id[1] = c.face_id[2] = -1;
  c.pending_count = 0;
  c.opaque = false;
  c.stuck = false;
}

bool CpuRayCaster::Impl::begin_next_walk(const TfTable& tf, const std::vector<Entry>& entries, std::size_t& next,
                                         double done, const WalkStats& stats, WalkCursor& c) const {
  while (next < entries.size()) {
    const Entry& e = entries[next++];
    // An entry before the last exit lies on a stretch already walked (a grazing touch). The
    // slack keeps a re-entry at the same depth: in a non-conforming mesh (hanging nodes) the
    // walk leaves a big tet through an unmatched face and the small tets behind it are entered
    // through their own unmatched faces, whose depth may round a few ulps below the exit's.
    if (e.t < done - reentry_slack) continue;
    begin_walk(tf, e, stats, c);
    return true;
  }
  return false;
}

void CpuRayCaster::Impl::end_walk(const TfTable& tf, double stop_transmittance, WalkCursor& c, Composite& acc,
                                  WalkStats& stats) const {
  if (!c.opaque && c.pending_count > 0)
    c.opaque = integrate_pending(tf, c.pending, c.pending_count, stop_transmittance, acc, stats);
  c.pending_count = 0;
  // A graze along the boundary (a few rounding units long) is not counted as an entry.
  if (!c.stuck && stats.length - c.length_before > kGrazeLength * mesh->bounds.diagonal()) ++stats.entries;
}

template <bool kShaded, class Geometry>
[[gnu::always_inline]] inline bool CpuRayCaster::Impl::step(const RayFrame& f, const Geometry& geo, const TfTable& tf,
                                                            const ShadeContext* shade, double stop_transmittance,
                                                            WalkCursor& c, Composite& acc, WalkStats& stats) const {
  const WalkTet& w = tets[static_cast<std::size_t>(c.tet)];
  const int* abc = kAbc[c.k];
  const std::int32_t id[4] = {w.v[c.k], w.v[abc[0]], w.v[abc[1]], w.v[abc[2]]};  // D, A, B, C
  // The entry face is the previous tet's exit face: reuse its projections (bit-identical to
  // projecting again); only a welded duplicate point (another id) is projected anew.
  Projected q[4];
  q[0] = geo.at(id[0]);
  for (int j = 1; j < 4; ++j) {
    if constexpr (Geometry::kReuseFace) {
      const bool m0 = id[j] == c.face_id[0], m1 = id[j] == c.face_id[1], m2 = id[j] == c.face_id[2];
      if (m0 | m1 | m2) [[likely]]
        q[j] = c.face_q[static_cast<int>(m1) + 2 * static_cast<int>(m2)];  // index, not branches
      else
        q[j] = geo.at(id[j]);
    } else {
      q[j] = geo.at(id[j]);
    }
  }
  double e_d[4];  // e(D, X) for X = A, B, C at 1..3
  for (int j = 1; j < 4; ++j) e_d[j] = edge_value(q[0], q[j]);
  int pattern = static_cast<int>(e_d[1] > 0) | static_cast<int>(e_d[2] > 0) << 1 | static_cast<int>(e_d[3] > 0) << 2;
  // The ray meets an edge's line: decided by the tie rule. One product tests the three (an
  // underflow to 0 only sends a rare step through the exact rule as well).
  if (e_d[1] * e_d[2] * e_d[3] == 0.0) [[unlikely]] {
    pattern = 0;
    for (int j = 1; j < 4; ++j)
      pattern |= static_cast<int>(detail::edge_positive(e_d[j], q[0], id[0], q[j], id[j])) << (j - 1);
  }
  const int x = kExitX[pattern], y = x == 3 ? 1 : x + 1;  // exit face (D, X, Y) by position
  const int opposite = abc[5 - x - y];  // local index of the vertex not on the exit face
  // Start fetching the next tet now so that the integration below hides the memory latency.
  const std::int32_t next = w.next[opposite];
  if (next >= 0) __builtin_prefetch(&tets[static_cast<std::size_t>(next >> 2)]);
  double wd = edge_value(q[x], q[y]);
  double wx = -e_d[y], wy = e_d[x];
  const double w3[3] = {std::max(0.0, wd), std::max(0.0, wx), std::max(0.0, wy)};
  double t_out = c.t_in, s_out = c.s_in;
  double l_out[3] = {0, 0, 0};
  if (w3[0] + w3[1] + w3[2] > 0) {
    const detail::FacePoint fp = geo.interpolate(w3, q[0], q[x], q[y]);
    t_out = fp.t;
    s_out = fp.mu[0] * geo.scalar(id[0]) + fp.mu[1] * geo.scalar(id[x]) + fp.mu[2] * geo.scalar(id[y]);
    if constexpr (kShaded) {
      const std::int32_t face[3] = {id[0], id[x], id[y]};
      shade->face_light(face, fp.mu, f.origin + f.d * t_out, l_out);
    }
  } else if constexpr (kShaded) {
    for (int i = 0; i < 3; ++i) l_out[i] = c.l_in[i];
  }
  const int p_out = tf.piece_near(s_out, c.p_in);
  if (t_out <= c.t_in) {
    t_out = c.t_in;
    if (++c.zero_steps > kMaxZeroLengthSteps) {
      c.stuck = true;
      return false;
    }
  } else {
    c.zero_steps = 0;
    // Only the part in front of the origin counts (the eye may sit inside the mesh; not with a
    // geometry whose points all lie in front of it).
    double t0 = c.t_in, s0 = c.s_in, clip = 0.0;
    int p0 = c.p_in;
    if constexpr (!Geometry::kInFront) {
      if (t0 < 0.0 && t_out > 0.0) {
        clip = -c.t_in / (t_out - c.t_in);
        s0 = c.s_in + (s_out - c.s_in) * clip;
        t0 = 0.0;
        p0 = tf.piece_or_nan(s0);
      }
    }
    if (Geometry::kInFront || (t_out > t0 && t0 >= 0.0)) {
      if constexpr (kShaded) {
        if (tf.emits(p0, p_out)) {
          const double phong = shade->phong(c.tet, f.d);
          Modulation mod;
          for (int i = 0; i < 3; ++i) {
            mod.front[i] = (c.l_in[i] + (l_out[i] - c.l_in[i]) * clip) * phong;
            mod.back[i] = l_out[i] * phong;
          }
          tf.integrate(s0, p0, s_out, p_out, t_out - t0, acc, &mod);
        }
        stats.length += t_out - t0;
        ++stats.segments;
        if (acc.transmittance < stop_transmittance) return false;
      } else {
        c.pending[c.pending_count++] = {s0, s_out, t_out - t0, p0, p_out};
        if (c.pending_count == kPendingSegments) {
          c.opaque = integrate_pending(tf, c.pending, c.pending_count, stop_transmittance, acc, stats);
          c.pending_count = 0;
          if (c.opaque) return false;
        }
      }
    }
  }
  c.t_in = t_out;
  c.s_in = s_out;
  c.p_in = p_out;
  if constexpr (kShaded)
    for (int i = 0; i < 3; ++i) c.l_in[i] = l_out[i];
  if constexpr (Geometry::kReuseFace) {
    c.face_id[0] = id[0];
    c.face_id[1] = id[x];
    c.face_id[2] = id[y];
    c.face_q[0] = q[0];
    c.face_q[1] = q[x];
    c.face_q[2] = q[y];
  }
  if (next < 0) return false;
  c.tet = next >> 2;
  c.k = next & 3;
  if (c.steps++ == tets.size()) return false;  // a straight line meets each tet only once
  return true;
}

template <class Geometry>
void CpuRayCaster::Impl::trace_ray(const RayFrame& f, const Geometry& geo, const TfTable& tf,
                                   const ShadeContext* shade, double stop_transmittance, std::vector<Entry>& entries,
                                   Composite& acc, WalkStats& stats, std::vector<RayRun>* runs) const {
  find_entries(f, geo, shade, entries);
  double done = -std::numeric_limits<double>::infinity();
  WalkCursor c;
  std::size_t next = 0;
  while (begin_next_walk(tf, entries, next, done, stats, c)) {
    const RunStart run{c.t_in, acc};
    if (shade != nullptr)
      while (step<true>(f, geo, tf, shade, stop_transmittance, c, acc, stats)) {
      }
    else
      while (step<false>(f, geo, tf, nullptr, stop_transmittance, c, acc, stats)) {
      }
    end_walk(tf, stop_transmittance, c, acc, stats);
    done = c.t_in;
    if (runs) add_run(run, done, acc, *runs);
    if (acc.transmittance < stop_transmittance) break;
  }
}

template <bool kShaded>
void CpuRayCaster::Impl::render_tile(const FrameContext& fc, int x0, int y0, int x1, int y1, RayJob* jobs,
                                     Image& image, PixelRuns* runs) const {
  const int width = x1 - x0, count = width * (y1 - y0);
  int next_pixel = 0;
  // A walk begins: where, and the composite so far, for its run.
  auto next_walk = [&](RayJob& j) {
    if (!begin_next_walk(fc.tf, j.entries, j.next_entry, j.done, j.stats, j.cursor)) return false;
    if (runs) j.run = RunStart{j.cursor.t_in, j.acc};
    return true;
  };
  auto finish = [&](const RayJob& j) { store_pixel(j.acc, image.pixel(j.x, j.y)); };
  // Fills a slot with the next pixel that has a walk to do (pixels without one are finished at
  // once); false when the tile has no pixel left.
  auto fill = [&](RayJob& j) {
    while (next_pixel < count) {
      j.x = x0 + next_pixel % width;
      j.y = y0 + next_pixel / width;
      ++next_pixel;
      const Ray ray = fc.camera.primary_ray(fc.camera_frame, j.x, j.y);
      j.frame = RayFrame(ray.origin, ray.direction);
      const std::size_t b = static_cast<std::size_t>(j.y / fc.bin) * fc.bins_x + static_cast<std::size_t>(j.x / fc.bin);
      const bool few = fc.bins.start[b + 1] - fc.bins.start[b] <= kMaxBinFaces;
      const std::int32_t* faces = fc.bins.faces.data();
      j.geo = ScreenGeometry(fc.screen, fc.basis, ray.direction, few ? faces + fc.bins.start[b] : nullptr,
                             few ? faces + fc.bins.start[b + 1] : nullptr);
      j.acc = Composite{};
      j.stats = WalkStats{};
      find_entries(j.frame, j.geo, fc.shade, j.entries);
      j.next_entry = 0;
      j.done = -std::numeric_limits<double>::infinity();
      if (next_walk(j)) return true;
      finish(j);
    }
    return false;
  };
  bool live[kRaysInFlight];
  for (int s = 0; s < kRaysInFlight; ++s) live[s] = fill(jobs[s]);
  for (;;) {
    bool any = false;
    for (int s = 0; s < kRaysInFlight; ++s) {
      if (!live[s]) continue;
      any = true;
      RayJob& j = jobs[s];
      {
        // The new point of the tet a later ray steps into next: its record was fetched one
        // round ago (step's prefetch); the point is not known before.
        const RayJob& later = jobs[(s + kPointLookahead) % kRaysInFlight];
        const WalkTet& lt = tets[static_cast<std::size_t>(later.cursor.tet)];
        __builtin_prefetch(&fc.screen[lt.v[later.cursor.k]]);
      }
      if (step<kShaded>(j.frame, j.geo, fc.tf, fc.shade, fc.stop_transmittance, j.cursor, j.acc, j.stats)) continue;
      end_walk(fc.tf, fc.stop_transmittance, j.cursor, j.acc, j.stats);
      j.done = j.cursor.t_in;
      if (runs) add_run(j.run, j.done, j.acc, (*runs)[static_cast<std::size_t>(j.y) * image.width + j.x]);
      if (j.acc.transmittance >= fc.stop_transmittance && next_walk(j)) continue;
      finish(j);
      live[s] = fill(j);
    }
    if (!any) break;
  }
}

CpuRayCaster::CpuRayCaster(std::shared_ptr<const TetMesh> mesh) : m_impl(std::make_unique<Impl>(std::move(mesh))) {}
CpuRayCaster::~CpuRayCaster() = default;

const TetMesh& CpuRayCaster::mesh() const { return *m_impl->mesh; }

void CpuRayCaster::move_points(std::shared_ptr<const TetMesh> moved) {
  detail::require_same_connectivity("CpuRayCaster::move_points", *m_impl->mesh, moved.get());
  m_impl->mesh = std::move(moved);
  m_impl->place_points();
}

Image CpuRayCaster::render(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
                           const RenderOptions& options) const {
  detail::check_frame_inputs("CpuRayCaster::render", *m_impl->mesh, scalars, tf, camera, options);
  Image image(camera.width, camera.height);
  m_impl->render_frame(scalars, tf, camera, options, image, nullptr, nullptr);
  return image;
}

void CpuRayCaster::render(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
                          const RenderOptions& options, RenderOutput& out) {
  detail::check_frame_inputs("CpuRayCaster::render", *m_impl->mesh, scalars, tf, camera, options);
  out.image = Image(camera.width, camera.height);
  out.runs = {};
  if (!options.ray_runs) return m_impl->render_frame(scalars, tf, camera, options, out.image, nullptr, nullptr);
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
  detail::RunsBudget budget(options.ray_runs_memory_bytes, pixels);
  budget.add(0);
  budget.check("CpuRayCaster::render");  // the per-pixel lists alone
  PixelRuns runs(pixels);
  m_impl->render_frame(scalars, tf, camera, options, out.image, &runs, &budget);
  budget.check("CpuRayCaster::render");
  out.runs = detail::flatten_runs(runs);
}

void CpuRayCaster::Impl::render_frame(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
                                      const RenderOptions& options, Image& image, PixelRuns* runs,
                                      detail::RunsBudget* budget) const {
  const double opacity = options.early_termination_opacity;
  const double stop_transmittance = opacity >= 1.0 ? 0.0 : 1.0 - opacity;
  const TfTable table(tf);
  const bool shaded = options.shading.model != LightingModel::none;
  const ShadeContext shade = shaded ? detail::make_shade_context(tets, points, point_ids.data(),
                                                                 scalars.data(), options.shading)
                                    : ShadeContext{};
  // With the whole mesh in front of the eye, projections are shared by all rays of the frame.
  const ScreenBasis basis = detail::screen_basis(camera);
  const std::vector<ScreenPoint> screen =
      detail::project_to_screen(basis, points, point_ids.data(), scalars.data(), mesh->bounds);
  const Camera::Frame camera_frame = camera.frame();
  constexpr int tile = 16;
  const int tiles_x = (camera.width + tile - 1) / tile, tiles_y = (camera.height + tile - 1) / tile;
  // Boundary faces binned by small screen tiles replace the per-ray BVH search: a bin of 2x2
  // pixels holds only the faces whose boxes hold one of its pixel centres, a handful at any
  // resolution. (Measured on a 1M-tet mesh at 512x512: 2x2 bins 8 % faster per frame than 4x4,
  // whose rays test more faces that miss them, and 4 % faster than one bin per pixel, which
  // lists the larger faces many more times.)
  constexpr int bin = 2;
  const int bins_x = (camera.width + bin - 1) / bin;
  const detail::ScreenBins bins =
      screen.empty() ? detail::ScreenBins{} : detail::bin_boundary_faces(triangles, screen, camera, bin);
  const FrameContext fc{camera, camera_frame, screen.data(), basis, bins, bin, bins_x,
                        table, shaded ? &shade : nullptr, stop_transmittance};
  parallel_for(static_cast<std::size_t>(tiles_x) * tiles_y, 4, [&](std::size_t begin, std::size_t end) {
    std::vector<Entry> entries;
    RayJob jobs[kRaysInFlight];
    for (std::size_t ti = begin; ti < end; ++ti) {
      const int x0 = static_cast<int>(ti % tiles_x) * tile, y0 = static_cast<int>(ti / tiles_x) * tile;
      const int x1 = std::min(x0 + tile, camera.width), y1 = std::min(y0 + tile, camera.height);
      if (budget && !budget->add(0)) return;  // over the runs' budget: render() throws
      const auto count_runs = [&] {
        for (int y = y0; budget && y < y1; ++y) {
          const std::size_t row = static_cast<std::size_t>(y) * camera.width;
          budget->add(*runs, row + x0, row + x1);
        }
      };
      if (!screen.empty()) {
        if (shaded)
          render_tile<true>(fc, x0, y0, x1, y1, jobs, image, runs);
        else
          render_tile<false>(fc, x0, y0, x1, y1, jobs, image, runs);
        count_runs();
        continue;
      }
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const Ray ray = camera.primary_ray(camera_frame, x, y);
          Composite acc;
          WalkStats stats;
          const RayFrame frame(ray.origin, ray.direction);
          const RayGeometry geo{frame, points.data(), point_ids.data(), scalars.data()};
          trace_ray(frame, geo, table, shaded ? &shade : nullptr, stop_transmittance, entries, acc, stats,
                    runs ? &(*runs)[static_cast<std::size_t>(y) * camera.width + x] : nullptr);
          store_pixel(acc, image.pixel(x, y));
        }
      count_runs();
    }
  });
}

RayTrace CpuRayCaster::trace(const std::vector<float>& scalars, const TransferFunction& tf, const Ray& ray) const {
  detail::check_render_inputs("CpuRayCaster::trace", *m_impl->mesh, scalars, tf);
  const double len = length(ray.direction);
  require(std::isfinite(len) && len > 0, "CpuRayCaster::trace: ray direction is zero or not finite");
  const TfTable table(tf);
  std::vector<Entry> entries;
  Composite acc;
  WalkStats stats;
  const RayFrame frame(ray.origin, ray.direction / len);
  const RayGeometry geo{frame, m_impl->points.data(), m_impl->point_ids.data(), scalars.data()};
  m_impl->trace_ray(frame, geo, table, nullptr, 0.0, entries, acc, stats);
  RayTrace r;
  for (int c = 0; c < 3; ++c) r.rgba[c] = acc.rgb[c];
  r.rgba[3] = 1.0 - acc.transmittance;
  r.optical_depth = acc.optical_depth;
  r.length_inside = stats.length;
  r.segments = stats.segments;
  r.entries = stats.entries;
  return r;
}

}  // namespace penumbra::render
