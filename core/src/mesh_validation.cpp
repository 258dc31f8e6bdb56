// SPDX-License-Identifier: BSD-3-Clause
// core/src/mesh_validation.cpp
#include "penumbra/core/mesh_validation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "penumbra/core/error.h"

namespace penumbra {
namespace {

// A fixed (not necessarily conforming) tet decomposition per cell type; only used to measure
// volume, so any valid decomposition of the VTK-ordered cell will do.
constexpr int kTetTets[1][4] = {{0, 1, 2, 3}};
constexpr int kPyrTets[2][4] = {{0, 1, 2, 4}, {0, 2, 3, 4}};
constexpr int kWedgeTets[3][4] = {{0, 1, 2, 3}, {1, 2, 3, 4}, {2, 3, 4, 5}};
constexpr int kHexTets[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};

template <std::size_t N>
double decomposed_volume6(const Vec3d* p, const int (&tets)[N][4]) {
  double v = 0;
  for (const auto& t : tets) v += signed_volume6(p[t[0]], p[t[1]], p[t[2]], p[t[3]]);
  return v;
}

std::string cell_name(std::size_t c) { return "cell " + std::to_string(c); }

// Per-item checks call this only on failure, so the message is never built on the hot path.
[[noreturn]] void fail(const std::string& message) { throw Error(ErrorCode::invalid_argument, message); }

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

// The mesh's size and position, from the bounds of its (finite) points, against the limits that its
// coordinates are computed within (kMinMeshExtent, kMaxMeshExtent, kMaxMeshOffset).
void check_extent(const Bounds& b, const std::string& who) {
  const double extent = b.diagonal();  // infinite beyond double's range: refused as too large
  if (!(extent >= kMinMeshExtent && extent <= kMaxMeshExtent))
    fail(who + "the mesh's extent (bounding-box diagonal) is " + number(extent) + " world units; meshes from " +
         number(kMinMeshExtent) + " to " + number(kMaxMeshExtent) +
         " are rendered, the picture being the same at any scale: express the coordinates in another unit");
  const double reach = std::max({std::fabs(b.lo.x), std::fabs(b.lo.y), std::fabs(b.lo.z), std::fabs(b.hi.x),
                                 std::fabs(b.hi.y), std::fabs(b.hi.z)});
  if (reach > kMaxMeshOffset * extent)
    fail(who + "the mesh lies " + number(reach / extent) + " extents from the origin (a coordinate of " +
         number(reach) + " for an extent of " + number(extent) + "); at most " + number(kMaxMeshOffset) +
         " are rendered, where double coordinates still resolve the mesh finer than float32 does: subtract an "
         "origin near the mesh from its coordinates");
}

}  // namespace

Bounds validate_points(const MeshView& m, const char* call) {
  const std::string who = std::string(call) + ": ";
  Bounds bounds;
  for (std::size_t i = 0; i < m.point_count(); ++i) {
    const Vec3d p = m.point(i);
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)))
      fail(who + "point " + std::to_string(i) + " has a NaN or infinite coordinate");
    bounds.extend(p);
  }
  check_extent(bounds, who);
  return bounds;
}

void validate_mesh(const MeshView& m, const char* call) {
  const std::string who = std::string(call) + ": ";
  require(m.points.count > 0, who + "mesh has no points");
  if (m.points.data == nullptr) {
    const bool any = m.axes[0].data || m.axes[1].data || m.axes[2].data;
    require(any, who + "points pointer is null (give interleaved xyz, or the three coordinate arrays)");
    for (int a = 0; a < 3; ++a)
      require(m.axes[a].data != nullptr, who + "coordinate array " + "xyz"[a] + " is null (the three arrays go together)");
  }
  require(m.point_type == ScalarType::float32 || m.point_type == ScalarType::float64,
          who + "points must be float32 or float64");
  require(m.connectivity.type == ScalarType::int32 || m.connectivity.type == ScalarType::int64,
          who + "connectivity must be int32 or int64");
  require(m.connectivity.count > 0 && m.connectivity.data != nullptr, who + "connectivity is empty or null");
  require(m.cell_types != nullptr && m.cell_type_count > 0, who + "cell types are missing");
  if (m.offsets.count == 0) {
    require(m.cell_type_count == 1, who + "offsets are required unless all cells share one type");
    const int n = cell_point_count(m.cell_types[0]);
    require(n > 0, who + "unsupported cell type " + std::to_string(m.cell_types[0]) +
                       " (expected 10 tetra, 12 hexahedron, 13 wedge or 14 pyramid)");
    require(m.connectivity.count % static_cast<std::size_t>(n) == 0,
            who + "connectivity has " + std::to_string(m.connectivity.count) +
                " ids, not a multiple of " + std::to_string(n) + " points per cell");
  } else {
    require(m.offsets.data != nullptr, who + "offsets pointer is null");
    require(m.offsets.type == ScalarType::int32 || m.offsets.type == ScalarType::int64,
            who + "offsets must be int32 or int64");
    require(m.cell_type_count == 1 || m.cell_type_count == m.offsets.count - 1,
            who + "cell types has " + std::to_string(m.cell_type_count) + " entries but offsets describe " +
                std::to_string(m.offsets.count - 1) + " cells");
  }
  const std::size_t np = m.point_count();
  validate_points(m, call);
  const std::size_t nc = m.cell_count();
  require(nc > 0, who + "mesh has no cells");
  for (std::size_t c = 0; c < nc; ++c) {
    const std::uint8_t type = m.cell_type(c);
    const int n = cell_point_count(type);
    if (n <= 0)
      fail(who + cell_name(c) + " has unsupported VTK cell type " + std::to_string(type) +
           " (expected 10 tetra, 12 hexahedron, 13 wedge or 14 pyramid)");
    const std::int64_t b = m.cell_begin(c);
    if (m.offsets.count > 0) {
      const std::int64_t e = m.offsets[c + 1];
      if (!(b >= 0 && e - b == n && static_cast<std::size_t>(e) <= m.connectivity.count))
        fail(who + cell_name(c) + " has offsets [" + std::to_string(b) + ", " + std::to_string(e) +
                  ") but a VTK type " + std::to_string(type) + " cell needs " + std::to_string(n) +
                  " ids within the " + std::to_string(m.connectivity.count) + " connectivity entries");
    }
    Vec3d p[8];
    Bounds box;
    for (int k = 0; k < n; ++k) {
      const std::int64_t id = m.connectivity[static_cast<std::size_t>(b + k)];
      if (!(id >= 0 && static_cast<std::size_t>(id) < np))
        fail(who + cell_name(c) + " references point " + std::to_string(id) + ", outside [0, " +
                  std::to_string(np) + ")");
      p[k] = m.point(static_cast<std::size_t>(id));
      box.extend(p[k]);
    }
    double v6 = 0;
    switch (type) {
      case 10: v6 = decomposed_volume6(p, kTetTets); break;
      case 12: v6 = decomposed_volume6(p, kHexTets); break;
      case 13: v6 = decomposed_volume6(p, kWedgeTets); break;
      default: v6 = decomposed_volume6(p, kPyrTets); break;
    }
    // Relative test: a cell whose volume is below 1e-12 of its bounding-box diagonal cubed is
    // degenerate at float precision (rays could not resolve it) and its gradient is undefined.
    const double d = box.diagonal();
    if (!(std::fabs(v6) > 6e-12 * d * d * d))
      fail(who + cell_name(c) + " has zero volume (degenerate VTK type " + std::to_string(type) + " cell)");
  }
}

}  // namespace penumbra
