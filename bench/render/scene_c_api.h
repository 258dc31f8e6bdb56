// SPDX-License-Identifier: BSD-3-Clause
// bench/render/scene_c_api.h -- a benchmark scene handed to the C API as a solver hands its mesh
#pragma once
#include <cstdint>

#include "penumbra/penumbra.h"
#include "scene.h"

namespace penumbra::bench {

/// The scene's tets as the C API takes them (float64 points, int64 ids, every cell a tet); the
/// points are left for the caller (they move in some benchmarks).
inline pnb_mesh_desc scene_mesh_desc(const Scene& scene) {
  static const std::uint8_t kTetra = 10;
  pnb_mesh_desc mesh PNB_MESH_DESC_INIT;
  mesh.point_count = static_cast<int64_t>(scene.point_count());
  mesh.point_type = PNB_FLOAT64;
  mesh.connectivity = scene.tets.data();
  mesh.connectivity_count = static_cast<int64_t>(scene.tets.size());
  mesh.index_type = PNB_INT64;
  mesh.cell_types = &kTetra;
  mesh.cell_types_count = 1;
  return mesh;
}

}  // namespace penumbra::bench
