// SPDX-License-Identifier: BSD-3-Clause
// bench/render/scene_views.h -- a benchmark scene as Penumbra's inputs
#pragma once
#include "penumbra/core/mesh_view.h"
#include "penumbra/render/camera.h"
#include "penumbra/render/transfer_function.h"
#include "scene.h"

namespace penumbra::bench {

/// The scene's tets as a mesh view (float64 points, int64 ids), valid while `scene` lives.
MeshView mesh_view(const Scene& scene);
/// The scene's single node list as colour and extinction points.
render::TransferFunction transfer_function(const Scene& scene);
/// The scene's camera at its image size, or at `width` x `height` when given.
render::Camera camera(const Scene& scene, int width = 0, int height = 0);

}  // namespace penumbra::bench
