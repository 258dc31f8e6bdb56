// SPDX-License-Identifier: BSD-3-Clause
// render/src/boundary_surface.cpp
#include "penumbra/render/boundary_surface.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <mutex>
#include <unordered_map>

namespace penumbra::render {
namespace {

// OpenMesh prints a line per refused triangle; the surface counts them instead, so its error
// stream is muted while surfaces are built and restored for the host program afterwards. The
// stream's switch is one global: contexts on several threads build surfaces at once, so the
// first builder mutes it and the last one restores it, under one lock.
class MutedOpenMeshErrors {
public:
  MutedOpenMeshErrors() {
    std::lock_guard<std::mutex> lock(mutex());
    if (state().builders++ == 0) {
      state().was_enabled = omerr().is_enabled();
      omerr().disable();
    }
  }
  ~MutedOpenMeshErrors() {
    std::lock_guard<std::mutex> lock(mutex());
    if (--state().builders == 0 && state().was_enabled) omerr().enable();
  }
  MutedOpenMeshErrors(const MutedOpenMeshErrors&) = delete;
  MutedOpenMeshErrors& operator=(const MutedOpenMeshErrors&) = delete;

private:
  struct State {
    int builders = 0;
    bool was_enabled = true;
  };
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static State& state() {
    static State s;
    return s;
  }
};

}  // namespace

struct BoundarySurface::Impl {
  OpenMesh::TriMesh_ArrayKernelT<> mesh;
};

BoundarySurface::BoundarySurface(const std::vector<Vec3d>& points,
                                 const std::vector<std::array<std::int32_t, 3>>& triangles)
    : m_impl(std::make_unique<Impl>()) {
  auto& m = m_impl->mesh;
  std::unordered_map<std::int32_t, OpenMesh::VertexHandle> handle;
  handle.reserve(triangles.size());
  auto vertex = [&](std::int32_t id) -> OpenMesh::VertexHandle {
    auto it = handle.find(id);
    if (it != handle.end()) return it->second;
    const Vec3d& p = points[static_cast<std::size_t>(id)];
    const auto h = m.add_vertex({static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
    handle.emplace(id, h);
    return h;
  };
  const MutedOpenMeshErrors muted;
  for (const auto& t : triangles) {
    // add_face refuses triangles that would make a non-manifold vertex or edge (two bodies
    // touching at a point); those are counted, not fatal: the renderer does not need them here.
    const auto f = m.add_face(vertex(t[0]), vertex(t[1]), vertex(t[2]));
    if (!f.is_valid()) ++m_rejected;
  }
}

BoundarySurface::~BoundarySurface() = default;

std::size_t BoundarySurface::vertex_count() const { return m_impl->mesh.n_vertices(); }
std::size_t BoundarySurface::triangle_count() const { return m_impl->mesh.n_faces(); }

bool BoundarySurface::is_closed() const {
  for (const auto e : m_impl->mesh.edges())
    if (m_impl->mesh.is_boundary(e)) return false;
  return m_rejected == 0;
}

std::size_t BoundarySurface::component_count() const {
  const auto& m = m_impl->mesh;
  std::vector<int> seen(m.n_faces(), 0);
  std::vector<OpenMesh::FaceHandle> stack;
  std::size_t components = 0;
  for (const auto f : m.faces()) {
    if (seen[static_cast<std::size_t>(f.idx())]) continue;
    ++components;
    stack.push_back(f);
    seen[static_cast<std::size_t>(f.idx())] = 1;
    while (!stack.empty()) {
      const auto g = stack.back();
      stack.pop_back();
      for (const auto n : m.ff_range(g))
        if (!seen[static_cast<std::size_t>(n.idx())]) {
          seen[static_cast<std::size_t>(n.idx())] = 1;
          stack.push_back(n);
        }
    }
  }
  return components;
}

long BoundarySurface::euler_characteristic() const {
  const auto& m = m_impl->mesh;
  return static_cast<long>(m.n_vertices()) - static_cast<long>(m.n_edges()) + static_cast<long>(m.n_faces());
}

double BoundarySurface::area() const {
  double a = 0;
  for (const auto f : m_impl->mesh.faces()) a += m_impl->mesh.calc_face_area(f);
  return a;
}

}  // namespace penumbra::render
