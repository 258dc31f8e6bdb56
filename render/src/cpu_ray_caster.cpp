// render/src/cpu_ray_caster.cpp -- boundary entries by BVH, tet walk by Plücker signs, exact
// segment integration
#include "penumbra/render/cpu_ray_caster.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "bvh.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "ray_frame.h"
#include "tf_table.h"

namespace penumbra::render {
namespace {

using detail::Composite;
using detail::edge_sign;
using detail::edge_value;
using detail::Projected;
using detail::RayFrame;
using detail::TfTable;

// Face k (opposite vertex k) listed with its normal pointing out of a positive tet.
constexpr int kFaceVertices[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
// Entered through face k, the other vertices A, B, C are ordered so that the three candidate
// exit faces, listed outward, are (D,A,B), (D,B,C), (D,C,A) with D the vertex k: (k,A,B,C) is an
// odd permutation of (0,1,2,3), like (3,0,1,2).
constexpr int kAbc[4][3] = {{1, 3, 2}, {0, 2, 3}, {1, 0, 3}, {0, 1, 2}};

// A tet for the walk: its points and, per face, the neighbour as (tet << 2 | face index of the
// shared face in the neighbour), or -1 on the boundary. 32 bytes: two per cache line.
struct WalkTet {
  std::int32_t v[4];
  std::int32_t next[4];
};

struct BoundaryTriangle {
  std::int32_t v[3];  // outward order
  std::int32_t tet, face;
};

// A boundary face where the ray enters the mesh.
struct Entry {
  double t, s;
  std::int32_t tet, face;
};

struct WalkStats {
  double length = 0;
  int segments = 0;
  int entries = 0;
  int aborted = 0;
};

constexpr int kMaxZeroLengthSteps = 1024;

}  // namespace

struct CpuRayCaster::Impl {
  std::shared_ptr<const TetMesh> mesh;
  std::vector<WalkTet> tets;
  std::vector<BoundaryTriangle> triangles;
  detail::Bvh bvh;

  explicit Impl(std::shared_ptr<const TetMesh> m);
  void find_entries(const RayFrame& f, const float* scalars, std::vector<Entry>& out) const;
  double walk(const RayFrame& f, const float* scalars, const TfTable& tf, const Entry& entry, double stop_transmittance,
              Composite& acc, WalkStats& stats) const;
  void trace_ray(const RayFrame& f, const float* scalars, const TfTable& tf, double stop_transmittance,
                 std::vector<Entry>& entries, Composite& acc, WalkStats& stats) const;
};

CpuRayCaster::Impl::Impl(std::shared_ptr<const TetMesh> m) : mesh(std::move(m)) {
  require(mesh != nullptr, "CpuRayCaster: mesh is null; expected a prepared TetMesh");
  const TetMesh& tm = *mesh;
  require(tm.neighbors.size() == tm.tets.size(), "CpuRayCaster: mesh has " + std::to_string(tm.neighbors.size()) +
                                                     " neighbour entries for " + std::to_string(tm.tets.size()) +
                                                     " tets; expected a mesh from prepare_tet_mesh");
  tets.resize(tm.tets.size());
  parallel_for(tets.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      for (int k = 0; k < 4; ++k) {
        tets[t].v[k] = tm.tets[t][k];
        const std::int32_t n = tm.neighbors[t][k];
        tets[t].next[k] = -1;
        if (n < 0) continue;
        // The shared face's index in the neighbour: the face whose neighbour is t.
        for (int j = 0; j < 4; ++j)
          if (tm.neighbors[static_cast<std::size_t>(n)][j] == static_cast<std::int32_t>(t)) tets[t].next[k] = (n << 2) | j;
      }
    }
  });
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
    tri.tet = bf.tet;
    tri.face = bf.face;
    triangles.push_back(tri);
    boxes.push_back(box);
  }
  bvh = detail::Bvh(boxes, 1e-9 * std::max(tm.bounds.diagonal(), 1e-300), 4);
}

void CpuRayCaster::Impl::find_entries(const RayFrame& f, const float* scalars, std::vector<Entry>& out) const {
  out.clear();
  const auto& pts = mesh->points;
  constexpr double inf = std::numeric_limits<double>::infinity();
  bvh.for_each_on_line(f.origin, f.d, -inf, inf, [&](std::int32_t i) {
    const BoundaryTriangle& tri = triangles[static_cast<std::size_t>(i)];
    Projected q[3];
    for (int j = 0; j < 3; ++j) q[j] = f.project(pts[static_cast<std::size_t>(tri.v[j])]);
    double e[3];  // e[j]: edge v[j] -> v[j+1]
    for (int j = 0; j < 3; ++j) {
      const int n = j == 2 ? 0 : j + 1;
      e[j] = edge_value(q[j], tri.v[j], q[n], tri.v[n]);
      // The ray enters through an outward face when it sees the face clockwise.
      if (edge_sign(e[j], q[j], tri.v[j], q[n], tri.v[n]) >= 0) return;
    }
    // Barycentric weight of a vertex: the opposite edge's value.
    const double w[3] = {std::max(0.0, -e[1]), std::max(0.0, -e[2]), std::max(0.0, -e[0])};
    const double sum = w[0] + w[1] + w[2];
    if (!(sum > 0)) return;
    Entry en;
    en.t = (w[0] * q[0].depth + w[1] * q[1].depth + w[2] * q[2].depth) / sum;
    en.s = (w[0] * scalars[tri.v[0]] + w[1] * scalars[tri.v[1]] + w[2] * scalars[tri.v[2]]) / sum;
    en.tet = tri.tet;
    en.face = tri.face;
    out.push_back(en);
  });
  // Usually one or two entries: insertion sort.
  for (std::size_t i = 1; i < out.size(); ++i)
    for (std::size_t j = i; j > 0 && out[j].t < out[j - 1].t; --j) std::swap(out[j], out[j - 1]);
}

// Walks from `entry` to the boundary exit (or until the ray is opaque); returns the exit depth.
double CpuRayCaster::Impl::walk(const RayFrame& f, const float* scalars, const TfTable& tf, const Entry& entry,
                                double stop_transmittance, Composite& acc, WalkStats& stats) const {
  const auto& pts = mesh->points;
  std::int32_t tet = entry.tet;
  int k = entry.face;
  double t_in = entry.t, s_in = entry.s;
  const double length_before = stats.length;
  int zero_steps = 0;
  for (std::size_t step = 0; step <= tets.size(); ++step) {
    const WalkTet& w = tets[static_cast<std::size_t>(tet)];
    const int* abc = kAbc[k];
    const std::int32_t id[4] = {w.v[k], w.v[abc[0]], w.v[abc[1]], w.v[abc[2]]};  // D, A, B, C
    Projected q[4];
    for (int j = 0; j < 4; ++j) q[j] = f.project(pts[static_cast<std::size_t>(id[j])]);
    double e_d[4];  // e(D, X) for X = A, B, C at 1..3
    bool pos[4];
    for (int j = 1; j < 4; ++j) {
      e_d[j] = edge_value(q[0], id[0], q[j], id[j]);
      pos[j] = edge_sign(e_d[j], q[0], id[0], q[j], id[j]) > 0;
    }
    // Exit through (D,A,B) iff e(D,A) > 0 >= e(D,B), and cyclically; exactly one holds for any
    // consistent sign pattern (the entry face's own edges are known to be on the inside).
    int x, y;  // exit face (D, X, Y) by position in id[]
    if (pos[1] && !pos[2]) { x = 1; y = 2; }
    else if (pos[2] && !pos[3]) { x = 2; y = 3; }
    else if (pos[3] && !pos[1]) { x = 3; y = 1; }
    else { x = 1; y = 2; }  // unreachable with consistent signs; the ray grazes D
    const int opposite = abc[5 - x - y];  // local index of the vertex not on the exit face
    double wd = edge_value(q[x], id[x], q[y], id[y]);
    double wx = -e_d[y], wy = e_d[x];
    wd = std::max(0.0, wd);
    wx = std::max(0.0, wx);
    wy = std::max(0.0, wy);
    const double sum = wd + wx + wy;
    double t_out = t_in, s_out = s_in;
    if (sum > 0) {
      const double inv = 1.0 / sum;
      t_out = (wd * q[0].depth + wx * q[x].depth + wy * q[y].depth) * inv;
      s_out = (wd * scalars[id[0]] + wx * scalars[id[x]] + wy * scalars[id[y]]) * inv;
    }
    if (t_out <= t_in) {
      t_out = t_in;
      if (++zero_steps > kMaxZeroLengthSteps) {
        ++stats.aborted;
        return t_out;
      }
    } else {
      zero_steps = 0;
      // Only the part in front of the origin counts (the eye may sit inside the mesh).
      double t0 = t_in, s0 = s_in;
      if (t0 < 0.0 && t_out > 0.0) {
        s0 = s_in + (s_out - s_in) * (-t_in / (t_out - t_in));
        t0 = 0.0;
      }
      if (t_out > t0 && t0 >= 0.0) {
        tf.integrate(s0, s_out, t_out - t0, acc);
        stats.length += t_out - t0;
        ++stats.segments;
        if (acc.transmittance < stop_transmittance) break;
      }
    }
    t_in = t_out;
    s_in = s_out;
    const std::int32_t next = w.next[opposite];
    if (next < 0) break;
    tet = next >> 2;
    k = next & 3;
    if (step == tets.size()) ++stats.aborted;  // a straight line meets each tet only once
  }
  if (stats.length > length_before) ++stats.entries;
  return t_in;
}

void CpuRayCaster::Impl::trace_ray(const RayFrame& f, const float* scalars, const TfTable& tf,
                                   double stop_transmittance, std::vector<Entry>& entries, Composite& acc,
                                   WalkStats& stats) const {
  find_entries(f, scalars, entries);
  double done = -std::numeric_limits<double>::infinity();
  for (const Entry& e : entries) {
    // An entry before the last exit lies on a stretch already walked (a grazing touch).
    if (e.t < done) continue;
    done = walk(f, scalars, tf, e, stop_transmittance, acc, stats);
    if (acc.transmittance < stop_transmittance) break;
  }
}

CpuRayCaster::CpuRayCaster(std::shared_ptr<const TetMesh> mesh) : m_impl(std::make_unique<Impl>(std::move(mesh))) {}
CpuRayCaster::~CpuRayCaster() = default;

const TetMesh& CpuRayCaster::mesh() const { return *m_impl->mesh; }

namespace {

void check_inputs(const char* call, const TetMesh& mesh, const std::vector<float>& scalars, const TransferFunction& tf) {
  require(scalars.size() == mesh.points.size(), std::string(call) + ": scalars has " + std::to_string(scalars.size()) +
                                                     " values but the mesh has " + std::to_string(mesh.points.size()) +
                                                     " points; expected one value per point");
  tf.validate();
}

}  // namespace

Image CpuRayCaster::render(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
                           const RenderOptions& options) const {
  check_inputs("CpuRayCaster::render", *m_impl->mesh, scalars, tf);
  require(camera.width > 0 && camera.height > 0, "CpuRayCaster::render: camera image size " +
                                                     std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                                                     "; expected positive width and height");
  const double opacity = options.early_termination_opacity;
  require(opacity > 0 && opacity <= 1, "CpuRayCaster::render: early_termination_opacity = " + std::to_string(opacity) +
                                           "; expected a value in (0, 1]");
  const double stop_transmittance = opacity >= 1.0 ? 0.0 : 1.0 - opacity;
  const TfTable table(tf);
  Image image(camera.width, camera.height);
  constexpr int tile = 16;
  const int tiles_x = (camera.width + tile - 1) / tile, tiles_y = (camera.height + tile - 1) / tile;
  parallel_for(static_cast<std::size_t>(tiles_x) * tiles_y, 4, [&](std::size_t begin, std::size_t end) {
    std::vector<Entry> entries;
    entries.reserve(64);
    for (std::size_t ti = begin; ti < end; ++ti) {
      const int x0 = static_cast<int>(ti % tiles_x) * tile, y0 = static_cast<int>(ti / tiles_x) * tile;
      for (int y = y0; y < std::min(y0 + tile, camera.height); ++y)
        for (int x = x0; x < std::min(x0 + tile, camera.width); ++x) {
          const Ray ray = camera.primary_ray(x, y);
          Composite acc;
          WalkStats stats;
          m_impl->trace_ray(RayFrame(ray.origin, ray.direction), scalars.data(), table, stop_transmittance, entries, acc,
                            stats);
          float* px = image.pixel(x, y);
          for (int c = 0; c < 3; ++c) px[c] = static_cast<float>(acc.rgb[c]);
          px[3] = static_cast<float>(1.0 - acc.transmittance);
        }
    }
  });
  return image;
}

RayTrace CpuRayCaster::trace(const std::vector<float>& scalars, const TransferFunction& tf, const Ray& ray) const {
  check_inputs("CpuRayCaster::trace", *m_impl->mesh, scalars, tf);
  const double len = length(ray.direction);
  require(std::isfinite(len) && len > 0, "CpuRayCaster::trace: ray direction is zero or not finite");
  const TfTable table(tf);
  std::vector<Entry> entries;
  Composite acc;
  WalkStats stats;
  m_impl->trace_ray(RayFrame(ray.origin, ray.direction / len), scalars.data(), table, 0.0, entries, acc, stats);
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
