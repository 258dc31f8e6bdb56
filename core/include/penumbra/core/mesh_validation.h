// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/mesh_validation.h
#pragma once
#include "penumbra/core/mesh_view.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra {

/// The extents (bounding-box diagonals) a mesh may have, in world units. Within them every
/// computation on coordinates stays in double's normal range: triple products of lengths a
/// hundred extents long (eye distances) neither overflow nor become subnormal.
inline constexpr double kMinMeshExtent = 1e-90;
inline constexpr double kMaxMeshExtent = 1e90;
/// How far from the origin a mesh may lie, in extents: double coordinates there still resolve
/// 2e-7 of the extent, finer than float32's own resolution of the mesh (6e-8 .. 1.2e-7) that the
/// GPU paths work at.
inline constexpr double kMaxMeshOffset = 1e9;

/// Checks a published mesh and throws Error(invalid_argument) naming the first offending cell
/// or point: unsupported cell type, offsets out of order or past the connectivity, a point id
/// out of range, a NaN/Inf coordinate, an extent outside [kMinMeshExtent, kMaxMeshExtent] or a
/// mesh farther than kMaxMeshOffset extents from the origin (with the limit and the remedy),
/// or a cell with zero volume (relative to its size). Inverted cells are not errors: preparation
/// re-orients them. `call` prefixes the message.
void validate_mesh(const MeshView& mesh, const char* call);

/// The point checks of validate_mesh alone (a NaN/Inf coordinate, the extent and offset limits),
/// for points that moved under a mesh already validated; returns the points' bounds.
Bounds validate_points(const MeshView& mesh, const char* call);

}  // namespace penumbra

PNB_PUBLIC_END
