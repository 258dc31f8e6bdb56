// SPDX-License-Identifier: BSD-3-Clause
// bench/render/scene.h -- the benchmark scenes shared by the Penumbra and the VTK programs
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/core/vec3.h"

namespace penumbra::bench {

/// One transfer-function node used for both colour and extinction. VTK's unstructured
/// integrators take their breakpoints from the colour function only, so every extinction
/// node must also be a colour node for both renderers to see the same piecewise-linear TF.
struct TfNode {
  double x;           ///< data value
  double r, g, b;     ///< linear RGB in [0,1]
  double extinction;  ///< extinction coefficient per world unit (>= 0)
};

/// Perspective camera as Penumbra's Camera::look_at and VTK's vtkCamera both take it.
struct SceneCamera {
  Vec3d eye, target, up;
  double fov_y_deg = 30.0;  ///< vertical field of view (vtkCamera's view angle)
};

/// A tet mesh with a per-point scalar field, a transfer function, a camera and a background.
struct Scene {
  std::string name;  ///< e.g. "holeblock-1m"
  std::string kind;  ///< "graded-nonconvex" or "grid-aligned"
  std::vector<double> points;          ///< x, y, z per point
  std::vector<std::int64_t> tets;      ///< 4 point ids per tet, VTK ordering
  std::vector<float> scalars;          ///< one value per point
  std::vector<TfNode> tf;              ///< sorted by x
  SceneCamera camera;
  int width = 512;
  int height = 512;
  float background[3] = {0.2f, 0.2f, 0.25f};

  std::size_t point_count() const { return points.size() / 3; }
  std::size_t tet_count() const { return tets.size() / 4; }
};

/// Names accepted by load_scene, in the order the benchmark runs them.
std::vector<std::string> scene_names();

/// Builds or loads scene `name`. Generated meshes are read from `data_dir` (bench/run.sh
/// creates them there). Throws penumbra::Error naming the scene or file on failure.
Scene load_scene(const std::string& name, const std::string& data_dir);

/// Hex digest of everything that determines the image (mesh, field, TF, camera, size,
/// background); cached reference images are keyed by it.
std::string scene_digest(const Scene& scene);

/// Path of the cached double-precision reference image of `scene` under `data_dir`.
std::string reference_path(const Scene& scene, const std::string& data_dir);

}  // namespace penumbra::bench
