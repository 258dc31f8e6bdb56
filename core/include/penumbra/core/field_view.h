// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/field_view.h
#pragma once
#include <string>
#include <vector>

#include "penumbra/core/mesh_view.h"

namespace penumbra {

/// Where a field's values live.
enum class Association : std::uint8_t { point, cell };

/// Non-owning view of one field of caller memory; valid only during the call that receives it.
/// `values` has one item per point (or cell); each item holds `components` values of `type`
/// (float32 or float64) contiguously.
struct FieldView {
  std::string name;
  Association association = Association::point;
  ScalarType type = ScalarType::float64;
  int components = 1;
  StridedSpan values;
};

/// How a field with several components becomes the rendered scalar.
enum class ComponentMode { magnitude, component };

/// Per-point float scalars of `field` on `mesh`, copied (the result is owned by the caller).
/// Cell fields are averaged to points over the cells that use each point (points used by no
/// cell get NaN). Vector fields give their magnitude, or component `component`.
/// Non-finite input values are kept as NaN: renderers treat a cell with a NaN vertex as empty.
/// Throws Error(invalid_argument) on a size mismatch, an unsupported type or a bad component.
std::vector<float> point_scalars(const MeshView& mesh, const FieldView& field,
                                 ComponentMode mode = ComponentMode::magnitude, int component = 0);

/// Finite value range of a scalar array; {0,0} when nothing is finite. `finite_count` receives
/// the number of finite values.
struct ValueRange { double lo = 0, hi = 0; std::size_t finite_count = 0; };
ValueRange finite_range(const std::vector<float>& values);

}  // namespace penumbra
