// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/mesh_validation.h
#pragma once
#include "penumbra/core/mesh_view.h"

namespace penumbra {

/// Checks a published mesh and throws Error(invalid_argument) naming the first offending cell
/// or point: unsupported cell type, offsets out of order or past the connectivity, a point id
/// out of range, a NaN/Inf coordinate, or a cell with zero volume (relative to its size).
/// Inverted cells are not errors: preparation re-orients them. `call` prefixes the message.
void validate_mesh(const MeshView& mesh, const char* call);

}  // namespace penumbra
