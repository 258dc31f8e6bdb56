// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/lighting/lighting_test_util.h -- meshes, fields and comparisons for the light-volume tests
#pragma once
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <vector>

#include "fixtures/meshes.h"
#include "penumbra/render/light_volume.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::lighting_test {

using render::Light;
using render::LightVolume;
using render::LightVolumeOptions;
using render::TetMesh;
using render::TransferFunction;

inline std::shared_ptr<const TetMesh> prepare(const fixtures::OwnedMesh& m) {
  return std::make_shared<const TetMesh>(render::prepare_tet_mesh(m.view()));
}

/// Freudenthal tet block over [lo, hi] with nx*ny*nz cubes.
inline std::shared_ptr<const TetMesh> tet_block(int nx, int ny, int nz, Vec3d lo, Vec3d hi,
                                                const fixtures::CellFilter& keep = {}) {
  return prepare(fixtures::block(fixtures::BlockCells::tets, nx, ny, nz, lo, hi, keep));
}

/// Extinction `tau` everywhere (constant transfer function); the scalar is irrelevant.
inline TransferFunction constant_tf(double tau) {
  TransferFunction tf;
  tf.colors = {{0, 1, 1, 1}};
  tf.opacities = {{0, tau}};
  return tf;
}

/// Extinction 0 for s <= 0, rising linearly to `tau` at s = 1 and constant beyond.
inline TransferFunction ramp_tf(double tau) {
  TransferFunction tf;
  tf.colors = {{0, 1, 1, 1}};
  tf.opacities = {{0, 0}, {1, tau}};
  return tf;
}

inline std::vector<float> field(const TetMesh& mesh, const std::function<double(const Vec3d&)>& f) {
  std::vector<float> s(mesh.points.size());
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = static_cast<float>(f(mesh.points[i]));
  return s;
}

inline Light directional(Vec3d dir, std::array<double, 3> colour = {1, 1, 1}) {
  return {Light::Kind::directional, dir, colour};
}
inline Light point_light(Vec3d pos, std::array<double, 3> colour = {1, 1, 1}) {
  return {Light::Kind::point, pos, colour};
}

/// Points that belong to at least one tet (fixtures' blocks with holes keep unused grid points).
inline std::vector<bool> used_points(const TetMesh& mesh) {
  std::vector<bool> used(mesh.points.size(), false);
  for (const auto& t : mesh.tets)
    for (auto v : t) used[static_cast<std::size_t>(v)] = true;
  return used;
}

/// Largest |rho - reference| over the mesh vertices selected by `use` (all when empty).
/// Largest |rho[p] - expect(x_p)| over the mesh points: a light field against a closed form.
inline double max_error_vs(const std::vector<float>& rho, const TetMesh& mesh,
                           const std::function<double(const Vec3d&)>& expect) {
  double worst = 0;
  for (std::size_t p = 0; p < mesh.points.size(); ++p) worst = std::max(worst, std::fabs(rho[p] - expect(mesh.points[p])));
  return worst;
}

inline double max_error_vs_reference(const LightVolume& lv, std::size_t k, const std::shared_ptr<const TetMesh>& mesh,
                                     const std::vector<float>& s, const TransferFunction& tf, const Light& light,
                                     const std::function<bool(const Vec3d&)>& use = {}) {
  const render::LightTransmittanceReference ref(mesh);
  const auto& rho = lv.light_rho(k);
  const auto used = used_points(*mesh);
  double worst = 0;
  for (std::size_t p = 0; p < mesh->points.size(); ++p) {
    if (!used[p] || (use && !use(mesh->points[p]))) continue;
    const double want = ref.transmittance(s, tf, lv.options().sigma_a, light, mesh->points[p], lv.options().occluders);
    worst = std::max(worst, std::fabs(static_cast<double>(rho[p]) - want));
  }
  return worst;
}

}  // namespace penumbra::lighting_test
