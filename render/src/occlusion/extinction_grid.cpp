// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/extinction_grid.cpp -- the transfer function's extinction on a regular grid
//
// The node location and the resampling are the light volume's level-0 grid (one implementation
// of "which tet holds this node"), so both lighting models see the same extinction.
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "../lighting/extinction_table.h"
#include "../lighting/level0_grid.h"
#include "penumbra/core/error.h"
#include "occlusion/occlusion_internals.h"

namespace penumbra::render {

void ExtinctionGrid::validate(const char* call) const {
  const std::string c = call;
  for (int a = 0; a < 3; ++a) {
    require(dims[a] >= 2, c + ": grid dims[" + std::to_string(a) + "] = " + std::to_string(dims[a]) + "; expected >= 2");
    require(std::isfinite(spacing[a]) && spacing[a] > 0,
            c + ": grid spacing[" + std::to_string(a) + "] = " + std::to_string(spacing[a]) + "; expected finite > 0");
    require(std::isfinite(lo[a]), c + ": grid origin is not finite");
  }
  const std::size_t n = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
  require(tau.size() == n, c + ": grid holds " + std::to_string(tau.size()) + " values; expected " + std::to_string(n));
}

struct ExtinctionResampler::Impl {
  std::shared_ptr<const TetMesh> mesh;
  lighting::Level0Grid grid;
};

ExtinctionResampler::ExtinctionResampler(std::shared_ptr<const TetMesh> mesh, int resolution, const Bounds& span)
    : m_impl(std::make_unique<Impl>()) {
  require(mesh != nullptr, "ExtinctionResampler: mesh is null");
  require(resolution >= 2, "ExtinctionResampler: resolution = " + std::to_string(resolution) + "; expected >= 2");
  require((!mesh->tets.empty() && !mesh->bounds.empty()) || !span.empty(), "ExtinctionResampler: the mesh has no tets");
  Bounds bounds = mesh->bounds;
  if (!span.empty()) {
    bounds.extend(span.lo);
    bounds.extend(span.hi);
  }
  const auto dims = lighting::Level0Grid::choose_dims(bounds, resolution, std::numeric_limits<std::size_t>::max() / 64, 0);
  m_impl->grid = lighting::Level0Grid(*mesh, bounds, dims, {});
  m_impl->mesh = std::move(mesh);
}

ExtinctionResampler::~ExtinctionResampler() = default;
ExtinctionResampler::ExtinctionResampler(ExtinctionResampler&&) noexcept = default;
ExtinctionResampler& ExtinctionResampler::operator=(ExtinctionResampler&&) noexcept = default;

std::array<int, 3> ExtinctionResampler::dims() const { return m_impl->grid.dims(); }

ExtinctionGrid ExtinctionResampler::resample(const std::vector<float>& point_scalars, const TransferFunction& tf) {
  const TetMesh& mesh = *m_impl->mesh;
  require(point_scalars.size() == mesh.points.size(),
          "ExtinctionResampler: " + std::to_string(point_scalars.size()) + " scalars for " +
              std::to_string(mesh.points.size()) + " points; expected one per point");
  tf.validate();
  lighting::Level0Grid& grid = m_impl->grid;
  grid.resample(mesh, point_scalars, lighting::ExtinctionTable(tf));
  ExtinctionGrid out;
  out.dims = grid.dims();
  out.lo = grid.lo();
  out.spacing = grid.spacing();
  out.tau = grid.tau();
  // A flat mesh axis gives zero spacing; give it the mean of the others so filtering stays finite.
  double sum = 0;
  int n = 0;
  for (int a = 0; a < 3; ++a)
    if (out.spacing[a] > 0) sum += out.spacing[a], ++n;
  for (int a = 0; a < 3; ++a)
    if (!(out.spacing[a] > 0)) out.spacing[a] = n ? sum / n : 1.0;
  return out;
}

ExtinctionGrid resample_extinction(const TetMesh& mesh, const std::vector<float>& point_scalars,
                                   const TransferFunction& tf, int resolution) {
  require(resolution >= 2, "resample_extinction: resolution = " + std::to_string(resolution) + "; expected >= 2");
  require(point_scalars.size() == mesh.points.size(),
          "resample_extinction: " + std::to_string(point_scalars.size()) + " scalars for " +
              std::to_string(mesh.points.size()) + " points; expected one per point");
  // A non-owning handle: the resampler lives only inside this call.
  ExtinctionResampler resampler(std::shared_ptr<const TetMesh>(&mesh, [](const TetMesh*) {}), resolution);
  return resampler.resample(point_scalars, tf);
}

}  // namespace penumbra::render
