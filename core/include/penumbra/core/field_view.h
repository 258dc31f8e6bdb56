// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/field_view.h
#pragma once
#include <string>
#include <vector>

#include "penumbra/core/mesh_view.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

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

/// Per-point scalars of `field` on `mesh` in double, copied (the result is owned by the caller).
/// Cell fields are averaged to points over the cells that use each point (points used by no
/// cell get NaN). Vector fields give their magnitude (computed without overflow or underflow for
/// any finite components), or component `component`.
/// Non-finite input values are kept as NaN: renderers treat a cell with a NaN vertex as empty.
/// Throws Error(invalid_argument) on a size mismatch, an unsupported type or a bad component.
std::vector<double> point_values(const MeshView& mesh, const FieldView& field,
                                 ComponentMode mode = ComponentMode::magnitude, int component = 0);

/// Finite value range of a scalar array; {0,0} when nothing is finite. `finite_count` receives
/// the number of finite values.
struct ValueRange { double lo = 0, hi = 0; std::size_t finite_count = 0; };
ValueRange finite_range(const std::vector<double>& values);

/// Normalised values lie within +-kNormalizedLimit: a value that far outside its range is beyond
/// every transfer function's breakpoints anyway, and float32 holds it.
inline constexpr double kNormalizedLimit = 1e30;

/// (v - lo) / (hi - lo) in double (no overflow for any finite lo < hi), clamped to
/// +-kNormalizedLimit; NaN stays NaN. Renderers see a field through this map, so that any finite
/// double field, whatever its magnitude and offset, keeps its variation when narrowed to float.
double normalize_value(double v, double lo, double hi);
/// normalize_value of each value, narrowed to float.
std::vector<float> normalize_values(const std::vector<double>& values, double lo, double hi);

}  // namespace penumbra

PNB_PUBLIC_END
