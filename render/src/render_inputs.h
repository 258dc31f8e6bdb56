// SPDX-License-Identifier: BSD-3-Clause
// render/src/render_inputs.h -- argument checks shared by the CPU, GPU and reference renderers
#pragma once
#include <string>
#include <vector>

#include "penumbra/core/error.h"
#include "penumbra/render/camera.h"
#include "penumbra/render/cpu_ray_caster.h"
#include "penumbra/render/tet_mesh.h"
#include "penumbra/render/transfer_function.h"

namespace penumbra::render::detail {

/// Throws Error(invalid_argument) naming `call` unless there is one scalar per mesh point and
/// the transfer function is valid.
inline void check_render_inputs(const char* call, const TetMesh& mesh, const std::vector<float>& scalars,
                                const TransferFunction& tf) {
  require(scalars.size() == mesh.points.size(), std::string(call) + ": scalars has " + std::to_string(scalars.size()) +
                                                     " values but the mesh has " + std::to_string(mesh.points.size()) +
                                                     " points; expected one value per point");
  tf.validate();
}

/// check_render_inputs, and the frame's own arguments: a positive image size, an early
/// termination opacity in (0, 1], valid shading.
inline void check_frame_inputs(const char* call, const TetMesh& mesh, const std::vector<float>& scalars,
                               const TransferFunction& tf, const Camera& camera, const RenderOptions& options) {
  check_render_inputs(call, mesh, scalars, tf);
  require(camera.width > 0 && camera.height > 0, std::string(call) + ": camera image size " +
                                                     std::to_string(camera.width) + "x" +
                                                     std::to_string(camera.height) +
                                                     "; expected positive width and height");
  const double opacity = options.early_termination_opacity;
  require(opacity > 0 && opacity <= 1, std::string(call) + ": early_termination_opacity = " +
                                           std::to_string(opacity) + "; expected a value in (0, 1]");
  options.shading.validate(call, mesh.points.size());
}

/// Throws Error(invalid_argument) naming `call` unless `moved` is `held` with its points moved:
/// the same points, tets and boundary (move_tet_mesh keeps them).
inline void require_same_connectivity(const char* call, const TetMesh& held, const TetMesh* moved) {
  require(moved != nullptr, std::string(call) + ": mesh is null; expected the moved mesh (move_tet_mesh)");
  require(moved->points.size() == held.points.size() && moved->tets == held.tets &&
              moved->boundary.size() == held.boundary.size(),
          std::string(call) + ": the moved mesh has " + std::to_string(moved->points.size()) + " points and " +
              std::to_string(moved->tet_count()) + " tets, not the held mesh's connectivity (" +
              std::to_string(held.points.size()) + " points, " + std::to_string(held.tet_count()) +
              " tets); make a renderer for a new mesh");
}

}  // namespace penumbra::render::detail
