// SPDX-License-Identifier: BSD-3-Clause
// bench/render/scene_views.cpp -- a benchmark scene as Penumbra's inputs
#include "scene_views.h"

namespace penumbra::bench {

MeshView mesh_view(const Scene& scene) {
  static const std::uint8_t tetra = 10;
  MeshView view;
  view.points = {reinterpret_cast<const std::byte*>(scene.points.data()), scene.point_count(), 3 * sizeof(double)};
  view.point_type = ScalarType::float64;
  view.connectivity = {scene.tets.data(), scene.tets.size(), ScalarType::int64};
  view.cell_types = &tetra;
  view.cell_type_count = 1;
  view.topology_version = 1;
  return view;
}

render::TransferFunction transfer_function(const Scene& scene) {
  render::TransferFunction tf;
  for (const TfNode& n : scene.tf) {
    tf.colors.push_back({n.x, n.r, n.g, n.b});
    tf.opacities.push_back({n.x, n.extinction});
  }
  return tf;
}

render::Camera camera(const Scene& scene, int width, int height) {
  const SceneCamera& c = scene.camera;
  return render::Camera::look_at(c.eye, c.target, c.up, c.fov_y_deg, width > 0 ? width : scene.width,
                                 height > 0 ? height : scene.height);
}

}  // namespace penumbra::bench
