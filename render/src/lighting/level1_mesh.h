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
  std::vector<std::int64_t> tet_offsets;   ///< point p's tets: tet_ids[tet_offsets[p] .. tet_offsets[p+1])
  std::vector<std::int32_t> tet_ids;
  std::vector<std::int8_t> tet_local;      ///< p's local index in that tet
  std::vector<std::int64_t> edge_offsets;  ///< point p's edge neighbours, sorted, unique
  std::vector<std::int32_t> edge_ids;
  std::vector<float> longest_edge;         ///< per point, its longest incident edge
  /// Per tet, where its record sits in Level1Field and in walk_tets: tets along a Morton curve
  /// of their centroids, so that the walks of neighbouring vertices (which a pass takes one after
  /// another) read neighbouring records instead of missing the cache at nearly every segment.
  std::vector<std::int32_t> field_slot;
  /// The tets as the walk reads them, at their field slots.
  std::vector<detail::WalkTet> walk_tets;
  /// Point p's incident tets as seen from p: star[tet_offsets[p] .. tet_offsets[p+1]), each the
  /// walk record and the face opposite p, so that finding where a walk from p starts reads
  /// them in sequence instead of loading every incident tet.
  std::vector<StarFace> star;
  double mean_edge = 0.0;
  double min_edge = 0.0;

  explicit Level1Topology(const TetMesh& mesh);
  Level1Topology() = default;
};

/// The scalar in one tet as a linear function of position, s(p) = offset + grad . p: one 32-byte
/// record per tet, so that a walk segment reads one cache line for its scalar (a base value at the
/// tet's first corner read the corner's id and point as well). NaN offset: a vertex without data
/// (no extinction).
struct LinearScalar {
  double offset;
  Vec3d grad;
  double at(const Vec3d& p) const { return offset + dot(grad, p); }
};

/// The scalar per tet, built per field: the walk evaluates it at segment ends without
/// barycentric solves. Indexed by Level1Topology::field_slot (a warm pass spent most of its time
/// waiting for these records while they were in mesh order).
struct Level1Field {
  std::vector<LinearScalar> linear;
  std::vector<float> scalars;  ///< per point (the walk interpolates them across faces)
  ExtinctionTable table;

  void build(const TetMesh& mesh, const Level1Topology& topology, const std::vector<float>& scalars,
             const TransferFunction& tf);
};

}  // namespace penumbra::render::lighting
