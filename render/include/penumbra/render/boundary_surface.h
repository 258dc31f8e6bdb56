// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/boundary_surface.h
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "penumbra/core/vec3.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::render {

/// The boundary of a prepared tet mesh as a triangle surface, held in an OpenMesh TriMesh
/// (kept out of this header). Triangles are oriented with outward normals. Immutable.
class BoundarySurface {
public:
  /// Builds the surface from outward-oriented triangles over `points` (ids index `points`).
  BoundarySurface(const std::vector<Vec3d>& points, const std::vector<std::array<std::int32_t, 3>>& triangles);
  ~BoundarySurface();
  BoundarySurface(const BoundarySurface&) = delete;
  BoundarySurface& operator=(const BoundarySurface&) = delete;

  std::size_t vertex_count() const;
  std::size_t triangle_count() const;
  /// Triangles OpenMesh could not add without making the surface non-manifold (they still
  /// take part in rendering through TetMesh::boundary).
  std::size_t rejected_triangles() const { return m_rejected; }
  /// True when every edge has a triangle on both sides: the domain is closed and
  /// every ray that enters it also leaves it.
  bool is_closed() const;
  /// Connected components of the surface: 1 for a simple solid, +1 per internal void.
  std::size_t component_count() const;
  /// Euler characteristic V - E + F summed over components (2 per sphere-like component,
  /// 0 for each through-hole's torus).
  long euler_characteristic() const;
  double area() const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  std::size_t m_rejected = 0;
};

}  // namespace penumbra::render

PNB_PUBLIC_END
