// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/prepared_mesh.h -- what a Context keeps of a published mesh (its files' own)
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "context.h"
#include "penumbra/render/light_volume.h"
#include "penumbra/render/occlusion.h"
#include "penumbra/render/renderer.h"
#include "penumbra/render/tet_mesh.h"
#include "rank_scattering.h"
#include "shared_points.h"
#include "view_cameras.h"

namespace penumbra::insitu {

struct Context::PreparedMesh {
  std::shared_ptr<const render::TetMesh> tets;
  std::unique_ptr<render::Renderer> renderer;  ///< the config's backend, or the CPU where "auto" fell back
  bool on_gpu = false;                         ///< renderer is the GPU's: lighting is solved there too
  std::vector<std::byte> connectivity, offsets;  ///< owned copies, caller's index type
  std::vector<std::uint8_t> cell_types;
  MeshView view;  ///< over the owned copies (points from the prepared mesh)
  Bounds global_bounds;  ///< of every rank's mesh: the cameras and the frame are the ranks' common ones
  std::vector<ViewCamera> cameras;
  /// Per config field entry, its light volume (model light-volume), made at the first step and
  /// kept across steps so that each step's light starts from the previous one.
  std::vector<std::unique_ptr<render::LightVolume>> light_volumes;
  /// Over several ranks: the points this rank shares with others (made at the first lit step),
  /// and per field entry its light with the shared points settled (SharedPoints).
  std::unique_ptr<SharedPoints> shared_points;
  std::vector<std::vector<float>> settled_light;
  /// Over several ranks with scattering: its solver over every rank's points, and per field entry
  /// the scattered light (the next step's start).
  std::unique_ptr<RankScattering> scattering;
  std::vector<std::vector<float>> scattered_light;
  /// Likewise for lighting model "occlusion".
  std::vector<std::unique_ptr<render::OcclusionLighting>> occlusions;
};

}  // namespace penumbra::insitu
