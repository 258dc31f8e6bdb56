// render/src/cpu_ray_caster.cpp -- boundary entries by BVH, tet walk by Plücker signs, exact
// segment integration
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
  double light[3];  // L(x) at the entry point (shaded renders only)
};

struct WalkStats {
  double length = 0;
  int segments = 0;
  int entries = 0;
  int aborted = 0;
};

// A segment walked but not yet integrated: a ray walks up to kPendingSegments tets, then
// integrates them in one go. The walk is a chain of dependent loads and arithmetic (tet record,
// new point, edge signs, exit face, next tet) and the integration is independent arithmetic per
// segment; interleaved step by step, each step's integration fills the processor's window so
// that the next step's chain cannot start early, while apart each runs at its own pace.
struct PendingSegment {
  double s0, s1, length;
  int p0, p1;  // transfer-function pieces of s0 and s1, -1 for NaN
};
constexpr int kPendingSegments = 16;

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
    // Skips NaN ends (a cell with no data) and stretches of zero extinction cheaply.
    if (g.p1 >= 0 && g.p0 >= 0 && !(g.p0 == g.p1 && tf.piece_empty(g.p0)))
      tf.integrate(g.s0, g.p0, g.s1, g.p1, g.length, acc);
    stats.length += g.length;
    ++stats.segments;
    if (acc.transmittance < stop_transmittance) return true;
  }
  return false;
}

}  // namespace

struct CpuRayCaster::Impl {
  std::shared_ptr<const TetMesh> mesh;
  std::vector<WalkTet> tets;
  std::vector<BoundaryTriangle> triangles;
  detail::Bvh bvh;
  double reentry_slack = 0;  // depth tolerance for re-entering at an exit (see trace_ray)

  explicit Impl(std::shared_ptr<const TetMesh> m);
  // Geometry: RayGeometry or ScreenGeometry (walk_geometry.h). `f` is the ray itself, for the
  // BVH and the shading.
  template <class Geometry>
  void find_entries(const RayFrame& f, const Geometry& geo, const ShadeContext* shade,
                    std::vector<Entry>& out) const;
  // kShaded: the emitted colour is modulated by `shade` (null otherwise); a separate
  // instantiation keeps the unshaded walk free of it.
  template <bool kShaded, class Geometry>
  double walk(const RayFrame& f, const Geometry& geo, const TfTable& tf,
              const ShadeContext* shade, const Entry& entry, double stop_transmittance, Composite& acc,
              WalkStats& stats) const;
  template <class Geometry>
  void trace_ray(const RayFrame& f, const Geometry& geo, const TfTable& tf,
                 const ShadeContext* shade, double stop_transmittance, std::vector<Entry>& entries, Composite& acc,
                 WalkStats& stats) const;
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
  tets = detail::walk_tets(tm, order);
  triangles.reserve(tm.boundary.size());
  std::vector<Bounds> boxes;
  boxes.reserve(tm.boundary.size());
  for (const auto& bf : tm.boundary) {
    const auto& tv = tm.tets[static_cast<std::size_t>(bf.tet)];
    BoundaryTriangle tri{};
    Bounds box;
    for (int j = 0; j < 3; ++j) {
      tri.v[j] = tv[kFaceVertices[bf.face][j]];
      box.extend(tm.points[static_cast<std::size_t>(tri.v[j])]);
    }
    tri.tet = rank[static_cast<std::size_t>(bf.tet)];
    tri.face = bf.face;
    triangles.push_back(tri);
    boxes.push_back(box);
  }
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
    double e[3];  // e[j]: edge v[j] -> v[j+1]
    for (int j = 0; j < 3; ++j) {
      const int n = j == 2 ? 0 : j + 1;
      e[j] = edge_value(q[j], q[n]);
      // The ray enters through an outward face when it sees the face clockwise.
      if (edge_sign(e[j], q[j], tri.v[j], q[n], tri.v[n]) >= 0) return;
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

// Walks from `entry` to the boundary exit (or until the ray is opaque); returns the exit depth.
template <bool kShaded, class Geometry>
double CpuRayCaster::Impl::walk(const RayFrame& f, const Geometry& geo, const TfTable& tf,
                                const ShadeContext* shade, const Entry& entry, double stop_transmittance,
                                Composite& acc, WalkStats& stats) const {
  std::int32_t tet = entry.tet;
  int k = entry.face;
  double t_in = entry.t, s_in = entry.s;
  double l_in[3] = {entry.light[0], entry.light[1], entry.light[2]}, l_out[3] = {0, 0, 0};
  int p_in = std::isnan(s_in) ? -1 : tf.piece(s_in);  // transfer-function piece, -1 for NaN
  const double length_before = stats.length;
  int zero_steps = 0;
  std::int32_t face_id[3] = {-1, -1, -1};
  Projected face_q[3];
  [[maybe_unused]] PendingSegment pending[kShaded ? 1 : kPendingSegments];
  [[maybe_unused]] int pending_count = 0;
  [[maybe_unused]] bool stopped = false;
  for (std::size_t step = 0; step <= tets.size(); ++step) {
    const WalkTet& w = tets[static_cast<std::size_t>(tet)];
    const int* abc = kAbc[k];
    const std::int32_t id[4] = {w.v[k], w.v[abc[0]], w.v[abc[1]], w.v[abc[2]]};  // D, A, B, C
    // The entry face is the previous tet's exit face: reuse its projections (bit-identical to
    // projecting again); only a welded duplicate point (another id) is projected anew.
    Projected q[4];
    q[0] = geo.at(id[0]);
    for (int j = 1; j < 4; ++j) {
      if constexpr (Geometry::kReuseFace) {
        const bool m0 = id[j] == face_id[0], m1 = id[j] == face_id[1], m2 = id[j] == face_id[2];
        if (m0 | m1 | m2) [[likely]]
          q[j] = face_q[static_cast<int>(m1) + 2 * static_cast<int>(m2)];  // index, not branches
        else
          q[j] = geo.at(id[j]);
      } else {
        q[j] = geo.at(id[j]);
      }
    }
    double e_d[4];  // e(D, X) for X = A, B, C at 1..3
    int pattern = 0;
    for (int j = 1; j < 4; ++j) {
      e_d[j] = edge_value(q[0], q[j]);
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
    double t_out = t_in, s_out = s_in;
    if (w3[0] + w3[1] + w3[2] > 0) {
      const detail::FacePoint fp = geo.interpolate(w3, q[0], q[x], q[y]);
      t_out = fp.t;
      s_out = fp.mu[0] * geo.scalar(id[0]) + fp.mu[1] * geo.scalar(id[x]) + fp.mu[2] * geo.scalar(id[y]);
      if constexpr (kShaded) {
        const std::int32_t face[3] = {id[0], id[x], id[y]};
        shade->face_light(face, fp.mu, f.origin + f.d * t_out, l_out);
      }
    } else if constexpr (kShaded) {
      for (int c = 0; c < 3; ++c) l_out[c] = l_in[c];
    }
    const int p_out = std::isnan(s_out) ? -1 : tf.piece_near(s_out, p_in);
    if (t_out <= t_in) {
      t_out = t_in;
      if (++zero_steps > kMaxZeroLengthSteps) {
        ++stats.aborted;
        break;
      }
    } else {
      zero_steps = 0;
      // Only the part in front of the origin counts (the eye may sit inside the mesh).
      double t0 = t_in, s0 = s_in, clip = 0.0;
      int p0 = p_in;
      if (t0 < 0.0 && t_out > 0.0) {
        clip = -t_in / (t_out - t_in);
        s0 = s_in + (s_out - s_in) * clip;
        t0 = 0.0;
        p0 = std::isnan(s0) ? -1 : tf.piece(s0);
      }
      if (t_out > t0 && t0 >= 0.0) {
        if constexpr (kShaded) {
          // Skips NaN ends (a cell with no data) and stretches of zero extinction cheaply.
          if (p_out >= 0 && p0 >= 0 && !(p0 == p_out && tf.piece_empty(p0))) {
            const double phong = shade->phong(tet, f.d);
            Modulation mod;
            for (int c = 0; c < 3; ++c) {
              mod.front[c] = (l_in[c] + (l_out[c] - l_in[c]) * clip) * phong;
              mod.back[c] = l_out[c] * phong;
            }
            tf.integrate(s0, p0, s_out, p_out, t_out - t0, acc, &mod);
          }
          stats.length += t_out - t0;
          ++stats.segments;
          if (acc.transmittance < stop_transmittance) break;
        } else {
          pending[pending_count++] = {s0, s_out, t_out - t0, p0, p_out};
          if (pending_count == kPendingSegments) {
            const bool opaque = integrate_pending(tf, pending, pending_count, stop_transmittance, acc, stats);
            pending_count = 0;
            if (opaque) {
              stopped = true;
              break;
            }
          }
        }
      }
    }
    t_in = t_out;
    s_in = s_out;
    p_in = p_out;
    if constexpr (kShaded)
      for (int c = 0; c < 3; ++c) l_in[c] = l_out[c];
    if constexpr (Geometry::kReuseFace) {
      face_id[0] = id[0];
      face_id[1] = id[x];
      face_id[2] = id[y];
      face_q[0] = q[0];
      face_q[1] = q[x];
      face_q[2] = q[y];
    }
    if (next < 0) break;
    tet = next >> 2;
    k = next & 3;
    if (step == tets.size()) ++stats.aborted;  // a straight line meets each tet only once
  }
  if constexpr (!kShaded)
    if (!stopped) integrate_pending(tf, pending, pending_count, stop_transmittance, acc, stats);
  // A graze along the boundary (a few rounding units long) is not counted as an entry.
  if (stats.length - length_before > kGrazeLength * mesh->bounds.diagonal()) ++stats.entries;
  return t_in;
}

template <class Geometry>
void CpuRayCaster::Impl::trace_ray(const RayFrame& f, const Geometry& geo, const TfTable& tf,
                                   const ShadeContext* shade, double stop_transmittance, std::vector<Entry>& entries,
                                   Composite& acc, WalkStats& stats) const {
  find_entries(f, geo, shade, entries);
  double done = -std::numeric_limits<double>::infinity();
  for (const Entry& e : entries) {
    // An entry before the last exit lies on a stretch already walked (a grazing touch). The
    // slack keeps a re-entry at the same depth: in a non-conforming mesh (hanging nodes) the
    // walk leaves a big tet through an unmatched face and the small tets behind it are entered
    // through their own unmatched faces, whose depth may round a few ulps below the exit's.
    if (e.t < done - reentry_slack) continue;
    done = shade != nullptr ? walk<true>(f, geo, tf, shade, e, stop_transmittance, acc, stats)
                            : walk<false>(f, geo, tf, nullptr, e, stop_transmittance, acc, stats);
    if (acc.transmittance < stop_transmittance) break;
  }
}

CpuRayCaster::CpuRayCaster(std::shared_ptr<const TetMesh> mesh) : m_impl(std::make_unique<Impl>(std::move(mesh))) {}
CpuRayCaster::~CpuRayCaster() = default;

const TetMesh& CpuRayCaster::mesh() const { return *m_impl->mesh; }

Image CpuRayCaster::render(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
                           const RenderOptions& options) const {
  detail::check_frame_inputs("CpuRayCaster::render", *m_impl->mesh, scalars, tf, camera, options);
  const double opacity = options.early_termination_opacity;
  const double stop_transmittance = opacity >= 1.0 ? 0.0 : 1.0 - opacity;
  const TfTable table(tf);
  const bool shaded = options.shading.model != LightingModel::none;
  const ShadeContext shade = shaded ? detail::make_shade_context(m_impl->tets, m_impl->mesh->points, scalars.data(),
                                                                 options.shading)
                                    : ShadeContext{};
  Image image(camera.width, camera.height);
  // With the whole mesh in front of the eye, projections are shared by all rays of the frame.
  const ScreenBasis basis = detail::screen_basis(camera);
  const std::vector<ScreenPoint> screen =
      detail::project_to_screen(basis, m_impl->mesh->points, scalars.data(), m_impl->mesh->bounds);
  const Camera::Frame camera_frame = camera.frame();
  constexpr int tile = 16;
  const int tiles_x = (camera.width + tile - 1) / tile, tiles_y = (camera.height + tile - 1) / tile;
  // Boundary faces binned by small screen tiles replace the per-ray BVH search: a bin of a few
  // pixels holds only the faces that may cover it, a handful at any resolution where faces
  // span a few pixels or more.
  constexpr int bin = 4;
  const int bins_x = (camera.width + bin - 1) / bin;
  const detail::ScreenBins bins =
      screen.empty() ? detail::ScreenBins{} : detail::bin_boundary_faces(m_impl->triangles, screen, camera, bin);
  parallel_for(static_cast<std::size_t>(tiles_x) * tiles_y, 4, [&](std::size_t begin, std::size_t end) {
    std::vector<Entry> entries;
    entries.reserve(64);
    for (std::size_t ti = begin; ti < end; ++ti) {
      const int x0 = static_cast<int>(ti % tiles_x) * tile, y0 = static_cast<int>(ti / tiles_x) * tile;
      for (int y = y0; y < std::min(y0 + tile, camera.height); ++y)
        for (int x = x0; x < std::min(x0 + tile, camera.width); ++x) {
          const Ray ray = camera.primary_ray(camera_frame, x, y);
          Composite acc;
          WalkStats stats;
          const RayFrame frame(ray.origin, ray.direction);
          if (screen.empty()) {
            m_impl->trace_ray(frame, RayGeometry{frame, m_impl->mesh->points.data(), scalars.data()}, table,
                              shaded ? &shade : nullptr, stop_transmittance, entries, acc, stats);
          } else {
            const std::size_t b = static_cast<std::size_t>(y / bin) * bins_x + static_cast<std::size_t>(x / bin);
            const bool few = bins.start[b + 1] - bins.start[b] <= kMaxBinFaces;
            const std::int32_t* faces = bins.faces.data();
            m_impl->trace_ray(frame,
                              ScreenGeometry(screen.data(), basis, ray.direction, few ? faces + bins.start[b] : nullptr,
                                             few ? faces + bins.start[b + 1] : nullptr),
                              table,
                              shaded ? &shade : nullptr, stop_transmittance, entries, acc, stats);
          }
          float* px = image.pixel(x, y);
          for (int c = 0; c < 3; ++c) px[c] = static_cast<float>(acc.rgb[c]);
          px[3] = static_cast<float>(1.0 - acc.transmittance);
        }
    }
  });
  return image;
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
  m_impl->trace_ray(frame, RayGeometry{frame, m_impl->mesh->points.data(), scalars.data()}, table, nullptr, 0.0,
                    entries, acc, stats);
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
