// SPDX-License-Identifier: BSD-3-Clause
// core/src/field_view.cpp
#include "penumbra/core/field_view.h"

#include <algorithm>
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
  // Scaled by the largest component, so that squares of 1e200 or 1e-200 neither overflow nor
  // underflow; a non-finite component makes the magnitude non-finite (no data).
  double largest = 0;
  for (int k = 0; k < f.components; ++k) largest = std::max(largest, std::fabs(read_value(f, item, k)));
  if (!(largest > 0) || !std::isfinite(largest)) return largest == 0 ? 0.0 : std::numeric_limits<double>::quiet_NaN();
  double s = 0;
  for (int k = 0; k < f.components; ++k) {
    const double v = read_value(f, item, k) / largest;
    s += v * v;
  }
  return largest * std::sqrt(s);
}

}  // namespace

std::vector<double> point_values(const MeshView& mesh, const FieldView& field, ComponentMode mode, int component) {
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
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();

  if (field.association == Association::point) {
    require(field.values.count == np, who + " has " + std::to_string(field.values.count) +
                                          " values but mesh has " + std::to_string(np) + " points");
    std::vector<double> out(np);
    for (std::size_t i = 0; i < np; ++i) {
      const double v = item_scalar(field, i, mode, component);
      out[i] = std::isfinite(v) ? v : nan;
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
  std::vector<double> out(np);
  for (std::size_t i = 0; i < np; ++i) out[i] = hits[i] && std::isfinite(sum[i]) ? sum[i] / hits[i] : nan;
  return out;
}

ValueRange finite_range(const std::vector<double>& values) {
  ValueRange r{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(), 0};
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    r.lo = std::min(r.lo, v);
    r.hi = std::max(r.hi, v);
    ++r.finite_count;
  }
  if (r.finite_count == 0) r.lo = r.hi = 0;
  return r;
}

double normalize_value(double v, double lo, double hi) {
  // Halved first: hi - lo and v - lo may exceed the largest double, their halves cannot; halving
  // is exact for normal numbers, so the quotient is the one of the unhalved difference.
  const double u = (0.5 * v - 0.5 * lo) / (0.5 * hi - 0.5 * lo);
  return std::isnan(u) ? u : std::clamp(u, -kNormalizedLimit, kNormalizedLimit);
}

std::vector<float> normalize_values(const std::vector<double>& values, double lo, double hi) {
  std::vector<float> out(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) out[i] = static_cast<float>(normalize_value(values[i], lo, hi));
  return out;
}

}  // namespace penumbra
