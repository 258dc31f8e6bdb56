// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level0_grid.h -- the regular level-0 grid of the light volume
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "extinction_table.h"
#include "penumbra/render/light_volume.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::render::lighting {

/// Nodes at lo + (i, j, k) * h over the mesh bounds, each knowing the tet that contains it
/// (found once per mesh by rasterising the tets), its mask and its resampled extinction.
class Level0Grid {
public:
  /// Bytes per node with `lights` lights: tet id, extinction, mask, rho per light, sweep scratch.
  static std::size_t bytes_per_node(std::size_t lights) { return 4 + 4 + 1 + 4 + 4 * (lights > 0 ? lights : 1); }
  // (the build's per-node depth test, 4 bytes, lives only while the grid is built)
  /// Dims for `resolution` nodes along the longest axis, reduced until the budget holds them.
  /// Throws Error(invalid_argument) when even 4 nodes per axis do not fit.
  static std::array<int, 3> choose_dims(const Bounds& bounds, int resolution, std::size_t budget_bytes,
                                        std::size_t lights);

  Level0Grid() = default;
  /// Nodes over `bounds` (a mesh's, or the union of every rank's); locates every node in the
  /// mesh (rasterising each tet over the nodes in its box) and marks occluder nodes.
  Level0Grid(const TetMesh& mesh, const Bounds& bounds, std::array<int, 3> dims, const std::vector<Bounds>& occluders);

  /// Extinction tau per node from the per-point scalars (NaN or outside: 0).
  void resample(const TetMesh& mesh, const std::vector<float>& scalars, const ExtinctionTable& table);
  /// Lets `combine` replace the extinction and the mask (LightVolume::combine_level0); the nodes
  /// of this grid's own tets keep their tets for the next resample. Returns whether the mask
  /// changed. Throws Error(internal_error) when `combine` resizes either.
  bool combine(const std::function<void(std::vector<float>&, std::vector<Level0Mask>&)>& combine);

  std::size_t size() const { return m_mask.size(); }
  std::size_t index(int i, int j, int k) const {
    return static_cast<std::size_t>(i) + static_cast<std::size_t>(m_dims[0]) * (static_cast<std::size_t>(j) + static_cast<std::size_t>(m_dims[1]) * static_cast<std::size_t>(k));
  }
  Vec3d position(int i, int j, int k) const { return {m_lo.x + i * m_h.x, m_lo.y + j * m_h.y, m_lo.z + k * m_h.z}; }
  const std::array<int, 3>& dims() const { return m_dims; }
  const Vec3d& lo() const { return m_lo; }
  const Vec3d& spacing() const { return m_h; }
  double max_spacing() const { return std::max(m_h.x, std::max(m_h.y, m_h.z)); }
  double min_spacing() const { return std::min(m_h.x, std::min(m_h.y, m_h.z)); }
  const std::vector<Level0Mask>& mask() const { return m_mask; }
  const std::vector<float>& tau() const { return m_tau; }

  /// Trilinear interpolation of a node field at p (clamped to the grid).
  double sample(const std::vector<float>& field, const Vec3d& p) const;
  /// As sample(), but when some of the 8 surrounding nodes are outside the mesh only those are
  /// used: at a point where a trace leaves the mesh they carry light that has not crossed the
  /// wall the trace came through.
  double sample_prefer_outside(const std::vector<float>& field, const Vec3d& p) const;

private:
  struct Cell {
    int i[3];
    double f[3];
  };
  Cell locate(const Vec3d& p) const;

  std::array<int, 3> m_dims{0, 0, 0};
  Vec3d m_lo, m_h;
  std::vector<std::int32_t> m_node_tet;
  std::vector<Level0Mask> m_mask;
  std::vector<float> m_tau;
};

}  // namespace penumbra::render::lighting
