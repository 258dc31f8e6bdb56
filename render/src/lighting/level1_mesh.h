// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/level1_mesh.h -- what the level-1 solve needs to know about the tet mesh
#pragma once
#include <cstdint>
#include <vector>

#include "extinction_table.h"
#include "penumbra/render/tet_mesh.h"
#include "walk_mesh.h"

namespace penumbra::render::lighting {

/// A tet of a point's star: its walk record << 2 | the point's local index k, and face k's
/// vertices in outward order.
struct StarFace {
  std::int32_t record;
  std::int32_t v[3];
};

/// Per-mesh connectivity, built once: the tets around each point and the edge neighbours of each
/// point (the scattering stencil), with the mean edge length.
struct Level1Topology {
  std::vector<std::int64_t> tet_offsets;   ///< point p's tets: star[tet_offsets[p] .. tet_offsets[p+1])
  std::vector<std::int64_t> edge_offsets;  ///< point p's edge neighbours, sorted, unique
  std::vector<std::int32_t> edge_ids;
  std::vector<float> longest_edge;         ///< per point, its longest incident edge
  /// The tets as the walk reads them, along a Morton curve of their centroids, so that the walks
  /// of neighbouring vertices (which a pass takes one after another) read neighbouring records
  /// instead of missing the cache at nearly every step.
  std::vector<detail::WalkTet> walk_tets;
  /// Point p's incident tets as seen from p: star[tet_offsets[p] .. tet_offsets[p+1]), each the
  /// walk record and the face opposite p, so that finding where a walk from p starts reads
  /// them in sequence instead of loading every incident tet.
  std::vector<StarFace> star;
  double mean_edge = 0.0;
  double min_edge = 0.0;

  explicit Level1Topology(const TetMesh& mesh);
  /// The edge lengths (longest_edge, mean_edge, min_edge) at `mesh`'s points: all that depends on
  /// the positions (the walk records keep the Morton order of the first positions: only
  /// locality depends on it), so a mesh whose points moved keeps the rest.
  void measure_edges(const TetMesh& mesh);
  Level1Topology() = default;
};

/// The field as level 1 reads it: the scalars per point (the walk interpolates them over the
/// faces it crosses) and the transfer function's extinction table.
struct Level1Field {
  std::vector<float> scalars;
  ExtinctionTable table;

  void build(const std::vector<float>& point_scalars, const TransferFunction& tf);
};

}  // namespace penumbra::render::lighting
