// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/occlusion/occlusion_test_util.h -- synthetic grids and meshes for the occlusion tests
#pragma once
#include <cmath>
#include <functional>
#include <memory>
#include <vector>

#include "fixtures/meshes.h"
#include "occlusion/occlusion_internals.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::occlusion_test {

using namespace penumbra::render;

constexpr double kPi = 3.14159265358979323846;

/// n^3 nodes over [lo, hi]^3 with tau = f(node position).
inline ExtinctionGrid grid(int n, double lo, double hi, const std::function<double(const Vec3d&)>& f) {
  ExtinctionGrid g;
  g.dims = {n, n, n};
  g.lo = {lo, lo, lo};
  const double h = (hi - lo) / (n - 1);
  g.spacing = {h, h, h};
  g.tau.resize(static_cast<std::size_t>(n) * n * n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) g.tau[g.index(i, j, k)] = static_cast<float>(f(g.position(i, j, k)));
  return g;
}

inline std::shared_ptr<const TetMesh> tet_block(int n, Vec3d lo, Vec3d hi, const fixtures::CellFilter& keep = {}) {
  return std::make_shared<const TetMesh>(
      prepare_tet_mesh(fixtures::block(fixtures::BlockCells::tets, n, n, n, lo, hi, keep).view()));
}

inline std::vector<float> field(const TetMesh& mesh, const std::function<double(const Vec3d&)>& f) {
  std::vector<float> s(mesh.points.size());
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = static_cast<float>(f(mesh.points[i]));
  return s;
}

/// Extinction `tau` for every scalar.
inline TransferFunction constant_tf(double tau) {
  TransferFunction tf;
  tf.colors = {{0, 1, 1, 1}};
  tf.opacities = {{0, tau}};
  return tf;
}

/// Extinction `tau` for s <= edge - width, 0 for s >= edge, linear between: with s the distance to
/// a centre this is a ball of radius about edge - width / 2.
inline TransferFunction ball_tf(double tau, double edge, double width) {
  TransferFunction tf;
  tf.colors = {{0, 1, 1, 1}};
  tf.opacities = {{edge - width, tau}, {edge, 0}};
  return tf;
}

/// Cosine-weighted visible fraction of a cone of half-angle beta whose axis passes through the
/// centre of an opaque ball (or disc) of angular radius gamma (thesis sec. 3.5.2 check).
inline double cone_past_ball(double gamma, double beta) {
  if (gamma >= beta) return 0.0;
  const double sg = std::sin(gamma), sb = std::sin(beta);
  return 1.0 - sg * sg / (sb * sb);
}

}  // namespace penumbra::occlusion_test
