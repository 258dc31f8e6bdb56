// render/src/render_inputs.h -- argument checks shared by the fast and the reference renderer
#pragma once
#include <string>
#include <vector>

#include "penumbra/core/error.h"
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

}  // namespace penumbra::render::detail
