// render/src/lighting/level1_mesh.h -- what the level-1 solve needs to know about the tet mesh
#pragma once
#include <cstdint>
#include <vector>

#include "extinction_table.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::render::lighting {

/// Per-mesh connectivity, built once: the tets around each point and the edge neighbours of each
/// point (the scattering stencil), with the mean edge length.
struct Level1Topology {
  std::vector<std::int64_t> tet_offsets;   ///< point p's tets: tet_ids[tet_offsets[p] .. tet_offsets[p+1])
  std::vector<std::int32_t> tet_ids;
  std::vector<std::int8_t> tet_local;      ///< p's local index in that tet
  std::vector<std::int64_t> edge_offsets;  ///< point p's edge neighbours, sorted, unique
  std::vector<std::int32_t> edge_ids;
  std::vector<float> longest_edge;         ///< per point, its longest incident edge
  /// Per tet, bit j: face j's canonical normal points inward (see canonical_face_inward), so the
  /// walk gets oriented face planes without a test per crossing.
  std::vector<std::uint8_t> face_inward;
  double mean_edge = 0.0;
  double min_edge = 0.0;

  explicit Level1Topology(const TetMesh& mesh);
  Level1Topology() = default;
};

/// The scalar as a linear function in each tet, s(p) = base + grad . (p - first vertex), built per
/// field: the walk evaluates it at segment ends without barycentric solves. A tet with a NaN
/// vertex has NaN base (no data, no extinction).
struct Level1Field {
  std::vector<double> base;
  std::vector<Vec3d> grad;
  ExtinctionTable table;

  void build(const TetMesh& mesh, const std::vector<float>& scalars, const TransferFunction& tf);
};

}  // namespace penumbra::render::lighting
