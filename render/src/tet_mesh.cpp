// SPDX-License-Identifier: BSD-3-Clause
// render/src/tet_mesh.cpp -- from a solver's MeshView to a render-ready TetMesh
#include "penumbra/render/tet_mesh.h"

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <limits>
#include <mutex>
#include <string>
#include <unordered_map>

#include "cell_split.h"
#include "penumbra/core/error.h"
#include "penumbra/core/mesh_validation.h"
#include "penumbra/core/thread_pool.h"
#include "penumbra/render/boundary_surface.h"
#include "walk_mesh.h"

namespace penumbra::render {
namespace {

using detail::kFaceVertices;

struct Bits3 {
  std::uint64_t x, y, z;
  bool operator==(const Bits3&) const = default;
};
struct Bits3Hash {
  std::size_t operator()(const Bits3& b) const noexcept {
    return std::hash<std::uint64_t>()(b.x * 0x9E3779B97F4A7C15ull ^ (b.y + 0x632BE59BD9B4E019ull) * 31 ^ b.z);
  }
};

std::uint64_t bits(double v) {
  if (v == 0.0) v = 0.0;  // -0 and +0 are the same place
  std::uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

// Maps every point to the smallest id of the points at exactly the same coordinates. Solvers
// that duplicate points along material or partition interfaces would otherwise get false
// internal boundaries (and rays would stop there).
std::vector<std::int32_t> weld_points(const std::vector<Vec3d>& points, std::vector<std::array<std::int32_t, 2>>& welds) {
  std::vector<std::int32_t> canon(points.size());
  std::unordered_map<Bits3, std::int32_t, Bits3Hash> first;
  first.reserve(points.size());
  welds.clear();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto [it, inserted] =
        first.try_emplace(Bits3{bits(points[i].x), bits(points[i].y), bits(points[i].z)}, static_cast<std::int32_t>(i));
    canon[i] = it->second;
    if (!inserted) welds.push_back({static_cast<std::int32_t>(i), it->second});
  }
  return canon;
}

void split_cells(const MeshView& view, const std::vector<std::int32_t>& canon, TetMesh& out) {
  const std::size_t nc = view.cell_count();
  std::vector<std::array<std::uint8_t, 4>> local;
  std::int64_t ids[8], key[8];
  out.tets.reserve(nc);
  out.source_cell.reserve(nc);
  for (std::size_t c = 0; c < nc; ++c) {
    const std::uint8_t type = view.cell_type(c);
    const int n = cell_point_count(type);
    const std::int64_t b = view.cell_begin(c);
    for (int k = 0; k < n; ++k) {
      ids[k] = view.connectivity[static_cast<std::size_t>(b + k)];
      key[k] = canon[static_cast<std::size_t>(ids[k])];
    }
    local.clear();
    detail::split_cell(type, key, local);
    for (const auto& t : local) {
      std::array<std::int32_t, 4> tet{};
      for (int k = 0; k < 4; ++k) tet[k] = static_cast<std::int32_t>(ids[t[k]]);
      out.tets.push_back(tet);
      out.source_cell.push_back(static_cast<std::int64_t>(c));
    }
  }
}

std::size_t orient_tets(TetMesh& m, const MeshView& view) {
  std::size_t flipped_input_tets = 0;
  for (std::size_t t = 0; t < m.tets.size(); ++t) {
    auto& v = m.tets[t];
    if (signed_volume6(m.points[v[0]], m.points[v[1]], m.points[v[2]], m.points[v[3]]) < 0) {
      std::swap(v[2], v[3]);
      if (view.cell_type(static_cast<std::size_t>(m.source_cell[t])) == 10) ++flipped_input_tets;
    }
  }
  return flipped_input_tets;
}

struct FaceRecord {
  std::array<std::int32_t, 3> key;  // sorted welded ids
  std::int32_t slot;                // tet * 4 + face
  bool operator<(const FaceRecord& o) const {
    if (key[0] != o.key[0]) return key[0] < o.key[0];
    if (key[1] != o.key[1]) return key[1] < o.key[1];
    if (key[2] != o.key[2]) return key[2] < o.key[2];
    return slot < o.slot;
  }
};

void build_adjacency(TetMesh& m, const std::vector<std::int32_t>& canon) {
  const std::size_t nt = m.tets.size();
  std::vector<FaceRecord> faces(nt * 4);
  parallel_for(nt, 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t)
      for (int f = 0; f < 4; ++f) {
        std::array<std::int32_t, 3> k{};
        for (int j = 0; j < 3; ++j) k[j] = canon[static_cast<std::size_t>(m.tets[t][kFaceVertices[f][j]])];
        std::sort(k.begin(), k.end());
        faces[t * 4 + f] = {k, static_cast<std::int32_t>(t * 4 + f)};
      }
  });
  std::sort(faces.begin(), faces.end());
  m.neighbors.assign(nt, {-1, -1, -1, -1});
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i > 2) {
      const auto cell = [&](std::size_t r) { return std::to_string(m.source_cell[static_cast<std::size_t>(faces[r].slot / 4)]); };
      throw Error(ErrorCode::invalid_argument, "face shared by " + std::to_string(j - i) +
                                                   " cells (overlapping or non-manifold mesh): cells " + cell(i) +
                                                   ", " + cell(i + 1) + ", " + cell(i + 2));
    }
    if (j - i == 2) {
      const std::int32_t a = faces[i].slot, b = faces[i + 1].slot;
      m.neighbors[static_cast<std::size_t>(a / 4)][a % 4] = b / 4;
      m.neighbors[static_cast<std::size_t>(b / 4)][b % 4] = a / 4;
    } else {
      m.boundary.push_back({faces[i].slot / 4, faces[i].slot % 4});
    }
    i = j;
  }
}

std::shared_ptr<const BoundarySurface> make_surface(const TetMesh& m, const std::vector<std::int32_t>& canon) {
  std::vector<std::array<std::int32_t, 3>> tris;
  tris.reserve(m.boundary.size());
  for (const auto& bf : m.boundary) {
    const auto& t = m.tets[static_cast<std::size_t>(bf.tet)];
    tris.push_back({canon[static_cast<std::size_t>(t[kFaceVertices[bf.face][0]])],
                    canon[static_cast<std::size_t>(t[kFaceVertices[bf.face][1]])],
                    canon[static_cast<std::size_t>(t[kFaceVertices[bf.face][2]])]});
  }
  return std::make_shared<const BoundarySurface>(m.points, tris);
}

// The tets' volume, and the volume the boundary encloses: each outward boundary face with the
// centre as apex, summed (divergence theorem). Relative to the centre, so that a mesh far from the
// origin keeps its precision.
void measure_volumes(TetMesh& m) {
  const Vec3d c = m.frame.center;
  double tets = 0, enclosed = 0;
  for (const auto& t : m.tets)
    tets += signed_volume6(m.points[static_cast<std::size_t>(t[0])] - c, m.points[static_cast<std::size_t>(t[1])] - c,
                           m.points[static_cast<std::size_t>(t[2])] - c, m.points[static_cast<std::size_t>(t[3])] - c);
  for (const BoundaryFace& f : m.boundary) {
    const auto& t = m.tets[static_cast<std::size_t>(f.tet)];
    Vec3d q[4];
    for (int k = 0; k < 4; ++k) q[k] = m.points[static_cast<std::size_t>(t[static_cast<std::size_t>(k)])] - c;
    q[f.face] = Vec3d{0, 0, 0};  // the face's tet with its apex moved to the centre
    enclosed += signed_volume6(q[0], q[1], q[2], q[3]);
  }
  m.tet_volume = tets / 6;
  m.enclosed_volume = enclosed / 6;
}

// Every tet keeps the orientation it was prepared with (positive volume), and every input cell a
// volume that rays can resolve (validate_mesh's relative test), after its points moved. The tets
// of a cell are consecutive (split_cells).
void require_upright_cells(const TetMesh& m, const char* call) {
  const std::size_t nt = m.tets.size();
  for (std::size_t begin = 0; begin < nt;) {
    const std::int64_t cell = m.source_cell[begin];
    std::size_t end = begin;
    double v6 = 0, smallest = HUGE_VAL;
    Bounds box;
    for (; end < nt && m.source_cell[end] == cell; ++end) {
      const auto& t = m.tets[end];
      const Vec3d& a = m.points[static_cast<std::size_t>(t[0])];
      const Vec3d& b = m.points[static_cast<std::size_t>(t[1])];
      const Vec3d& c = m.points[static_cast<std::size_t>(t[2])];
      const Vec3d& d = m.points[static_cast<std::size_t>(t[3])];
      const double v = signed_volume6(a, b, c, d);
      smallest = std::min(smallest, v);
      v6 += v;
      for (const Vec3d* p : {&a, &b, &c, &d}) box.extend(*p);
    }
    const double size = box.diagonal();
    if (!(smallest > 0) || !(v6 > 6e-12 * size * size * size)) {
      char text[320];
      std::snprintf(text, sizeof text,
                    "%s: cell %lld is %s by the points' motion (volume %.6g, smallest of its %zu tets %.6g, for a size of "
                    "%.6g): a moving mesh keeps every cell's orientation; publish a new topology_version after "
                    "remeshing",
                    call, static_cast<long long>(cell), smallest < 0 ? "inverted" : "flattened", v6 / 6, end - begin,
                    smallest / 6, size);
      throw Error(ErrorCode::invalid_argument, text);
    }
    begin = end;
  }
}

}  // namespace

bool TetMesh::tangled() const {
  // Rounding of the two sums stays below 1e-12 of the volume on meshes of millions of tets.
  return std::fabs(tet_volume - enclosed_volume) > 1e-9 * std::fabs(tet_volume);
}

TetMesh prepare_tet_mesh(const MeshView& view, const char* call) {
  validate_mesh(view, call);
  require(view.point_count() < static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()),
          std::string(call) + ": more than 2^31-1 points are not supported");
  TetMesh m;
  m.topology_version = view.topology_version;
  m.points.resize(view.point_count());
  for (std::size_t i = 0; i < m.points.size(); ++i) {
    m.points[i] = view.point(i);
    m.bounds.extend(m.points[i]);
  }
  m.frame = LocalFrame::of(m.bounds);
  const auto canon = weld_points(m.points, m.welds);
  m.welded_points = m.welds.size();
  split_cells(view, canon, m);
  require(m.tets.size() < static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max() / 4),
          std::string(call) + ": more than 2^29 tets are not supported");
  m.reoriented_tets = orient_tets(m, view);
  build_adjacency(m, canon);
  m.surface = make_surface(m, canon);
  measure_volumes(m);
  return m;
}

double smallest_altitude(const TetMesh& m) {
  std::mutex mutex;
  double smallest = HUGE_VAL;
  parallel_for(m.tets.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    double local = HUGE_VAL;
    for (std::size_t t = b; t < e; ++t) {
      Vec3d p[4];
      for (int k = 0; k < 4; ++k) p[k] = m.points[static_cast<std::size_t>(m.tets[t][static_cast<std::size_t>(k)])] - m.frame.center;
      const double v6 = signed_volume6(p[0], p[1], p[2], p[3]);
      // 6V = |face normal| x altitude for each face: the largest face gives the smallest altitude.
      double largest = 0;
      for (const auto& f : kFaceVertices)
        largest = std::max(largest, length(cross(p[f[1]] - p[f[0]], p[f[2]] - p[f[0]])));
      if (largest > 0) local = std::min(local, v6 / largest);
    }
    const std::lock_guard lock(mutex);
    smallest = std::min(smallest, local);
  });
  return smallest;
}

bool keeps_welds(const TetMesh& prepared, const MeshView& moved) {
  for (const auto& [point, first] : prepared.welds) {
    const Vec3d a = moved.point(static_cast<std::size_t>(point)), b = moved.point(static_cast<std::size_t>(first));
    if (bits(a.x) != bits(b.x) || bits(a.y) != bits(b.y) || bits(a.z) != bits(b.z)) return false;
  }
  return true;
}

TetMesh move_tet_mesh(const TetMesh& prepared, const MeshView& moved, const char* call) {
  require(moved.point_count() == prepared.points.size(),
          std::string(call) + ": the moved mesh has " + std::to_string(moved.point_count()) + " points; the prepared one has " +
              std::to_string(prepared.points.size()));
  TetMesh m;
  m.bounds = validate_points(moved, call);
  m.frame = LocalFrame::of(m.bounds);
  m.points.resize(prepared.points.size());
  parallel_for(m.points.size(), 1 << 15, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) m.points[i] = moved.point(i);
  });
  m.tets = prepared.tets;
  m.source_cell = prepared.source_cell;
  require_upright_cells(m, call);
  m.neighbors = prepared.neighbors;
  m.boundary = prepared.boundary;
  m.welds = prepared.welds;
  m.welded_points = prepared.welded_points;
  m.reoriented_tets = prepared.reoriented_tets;
  m.topology_version = prepared.topology_version;
  m.surface = prepared.surface;  // its topology is the mesh's; rebuilding it would cost a third of the update
  measure_volumes(m);
  return m;
}

}  // namespace penumbra::render
