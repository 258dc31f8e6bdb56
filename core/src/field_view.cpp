// SPDX-License-Identifier: BSD-3-Clause
// core/src/field_view.cpp
#include "penumbra/core/field_view.h"

#include <cmath>
#include <limits>

#include "penumbra/core/error.h"

namespace penumbra {
namespace {

double read_value(const FieldView& f, std::size_t item, int comp) {
  const std::byte* p = f.values.at(item);
  return f.type == ScalarType::float32 ? reinterpret_cast<const float*>(p)[comp]
                                       : reinterpret_cast<const double*>(p)[comp];
}

double item_scalar(const FieldView& f, std::size_t item, ComponentMode mode, int component) {
  if (f.components == 1) return read_value(f, item, 0);
  if (mode == ComponentMode::component) return read_value(f, item, component);
  double s = 0;
  for (int k = 0; k < f.components; ++k) {
    const double v = read_value(f, item, k);
    s += v * v;
  }
  return std::sqrt(s);
}

}  // namespace

std::vector<float> point_scalars(const MeshView& mesh, const FieldView& field, ComponentMode mode, int component) {
  const std::string who = "field '" + field.name + "'";
  require(field.type == ScalarType::float32 || field.type == ScalarType::float64,
          who + ": values must be float32 or float64");
  require(field.components >= 1, who + ": components must be >= 1, got " + std::to_string(field.components));
  require(mode == ComponentMode::magnitude || (component >= 0 && component < field.components),
          who + ": component " + std::to_string(component) + " out of range [0, " +
              std::to_string(field.components) + ")");
  require(field.values.count == 0 || field.values.data != nullptr, who + ": values pointer is null");
  const std::size_t np = mesh.point_count();
  const std::size_t nc = mesh.cell_count();
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();

  if (field.association == Association::point) {
    require(field.values.count == np, who + " has " + std::to_string(field.values.count) +
                                          " values but mesh has " + std::to_string(np) + " points");
    std::vector<float> out(np);
    for (std::size_t i = 0; i < np; ++i) {
      const double v = item_scalar(field, i, mode, component);
      out[i] = std::isfinite(v) ? static_cast<float>(v) : nan;
    }
    return out;
  }

  require(field.values.count == nc, who + " has " + std::to_string(field.values.count) +
                                        " values but mesh has " + std::to_string(nc) + " cells");
  // Cell data is averaged onto the points of each cell; a NaN cell poisons its points, so that
  // "no data" stays visible instead of being blended into its neighbours.
  std::vector<double> sum(np, 0.0);
  std::vector<std::uint32_t> hits(np, 0);
  for (std::size_t c = 0; c < nc; ++c) {
    const double v = item_scalar(field, c, mode, component);
    const std::int64_t b = mesh.cell_begin(c);
    const int n = cell_point_count(mesh.cell_type(c));
    for (int k = 0; k < n; ++k) {
      const auto p = static_cast<std::size_t>(mesh.connectivity[static_cast<std::size_t>(b + k)]);
      sum[p] += std::isfinite(v) ? v : std::numeric_limits<double>::quiet_NaN();
      ++hits[p];
    }
  }
  std::vector<float> out(np);
  for (std::size_t i = 0; i < np; ++i) out[i] = hits[i] ? static_cast<float>(sum[i] / hits[i]) : nan;
  return out;
}

ValueRange finite_range(const std::vector<float>& values) {
  ValueRange r{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(), 0};
  for (float v : values) {
    if (!std::isfinite(v)) continue;
    r.lo = std::min<double>(r.lo, v);
    r.hi = std::max<double>(r.hi, v);
    ++r.finite_count;
  }
  if (r.finite_count == 0) r.lo = r.hi = 0;
  return r;
}

}  // namespace penumbra
