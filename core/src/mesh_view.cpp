// SPDX-License-Identifier: BSD-3-Clause
// core/src/mesh_view.cpp
#include "penumbra/core/mesh_view.h"

namespace penumbra {

std::size_t MeshView::cell_count() const {
  if (offsets.count > 0) return offsets.count - 1;
  if (cell_type_count == 1) {
    const int n = cell_point_count(cell_types[0]);
    return n > 0 ? connectivity.count / static_cast<std::size_t>(n) : 0;
  }
  return cell_type_count;
}

std::int64_t MeshView::cell_begin(std::size_t c) const {
  if (offsets.count > 0) return offsets[c];
  return static_cast<std::int64_t>(c) * cell_point_count(cell_types[0]);
}

Vec3d MeshView::point(std::size_t i) const {
  if (!points.data) {
    auto coordinate = [&](int a) {
      const std::byte* p = axes[a].at(i);
      return point_type == ScalarType::float32 ? double(*reinterpret_cast<const float*>(p))
                                               : *reinterpret_cast<const double*>(p);
    };
    return {coordinate(0), coordinate(1), coordinate(2)};
  }
  const std::byte* p = points.at(i);
  if (point_type == ScalarType::float32) {
    const float* f = reinterpret_cast<const float*>(p);
    return {f[0], f[1], f[2]};
  }
  const double* d = reinterpret_cast<const double*>(p);
  return {d[0], d[1], d[2]};
}

}  // namespace penumbra
