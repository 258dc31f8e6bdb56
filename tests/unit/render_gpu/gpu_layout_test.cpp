// SPDX-License-Identifier: BSD-3-Clause
// The buffers the shader reads: mesh layout, boundary BVH, transfer-function pieces, series.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "fixtures/meshes.h"
#include "gpu/gpu_mesh_layout.h"
#include "gpu/gpu_tf_layout.h"
#include "segment_integral.h"

namespace penumbra {
namespace {

using render::gpu::BvhNode;

render::TetMesh holed_mesh() { return render::prepare_tet_mesh(fixtures::tet_block_with_hole(6).view()); }

TEST(GpuMeshLayout, NeighbourLinksAreMutualAndShareTheFace) {
  const auto mesh = holed_mesh();
  const auto g = render::gpu::build_gpu_mesh_layout(mesh);
  ASSERT_EQ(g.tet_vertices.size(), mesh.tets.size());
  std::size_t boundary_faces = 0;
  for (std::size_t t = 0; t < g.tet_next.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      const std::int32_t n = g.tet_next[t][k];
      if (n < 0) {
        ++boundary_faces;
        continue;
      }
      const auto u = static_cast<std::size_t>(n >> 2);
      const int j = n & 3;
      ASSERT_EQ(g.tet_next[u][j], static_cast<std::int32_t>(t << 2 | k));
      std::multiset<std::int32_t> a, b;
      for (int i = 0; i < 4; ++i) {
        if (i != k) a.insert(g.tet_vertices[t][i]);
        if (i != j) b.insert(g.tet_vertices[u][i]);
      }
      ASSERT_EQ(a, b);
    }
  EXPECT_EQ(boundary_faces, mesh.boundary.size());
}

TEST(GpuMeshLayout, BvhHoldsEveryBoundaryTriangleOnceInsideItsBoxes) {
  const auto mesh = holed_mesh();
  const auto g = render::gpu::build_gpu_mesh_layout(mesh);
  ASSERT_EQ(g.triangles.size(), mesh.boundary.size());
  std::vector<int> seen(g.triangles.size(), 0);
  auto inside = [](const BvhNode& n, const float* p) {
    for (int a = 0; a < 3; ++a)
      if (p[a] < n.lo[a] || p[a] > n.hi[a]) return false;
    return true;
  };
  std::vector<std::int32_t> stack = {0};
  while (!stack.empty()) {
    const BvhNode& n = g.nodes[static_cast<std::size_t>(stack.back())];
    stack.pop_back();
    if (n.count == 0) {
      for (std::int32_t c : {n.first, n.first + 1}) {
        const BvhNode& child = g.nodes[static_cast<std::size_t>(c)];
        for (int a = 0; a < 3; ++a) {
          EXPECT_LE(n.lo[a], child.lo[a]);
          EXPECT_GE(n.hi[a], child.hi[a]);
        }
        stack.push_back(c);
      }
      continue;
    }
    EXPECT_LE(n.count, 4);
    for (std::int32_t i = n.first; i < n.first + n.count; ++i) {
      ++seen[static_cast<std::size_t>(i)];
      const auto& tri = g.triangles[static_cast<std::size_t>(i)];
      for (int j = 0; j < 3; ++j) EXPECT_TRUE(inside(n, &g.points[3 * static_cast<std::size_t>(tri[j])]));
      // The triangle is a boundary face of the tet it names.
      EXPECT_EQ(g.tet_next[static_cast<std::size_t>(tri[3] >> 2)][tri[3] & 3], -1);
    }
  }
  for (int s : seen) EXPECT_EQ(s, 1);
}

TEST(GpuMeshLayout, PointsAreStoredInTheLocalFrame) {
  auto owned = fixtures::block(fixtures::BlockCells::tets, 2, 2, 2, {1e6, 1e6, 1e6}, {1e6 + 1, 1e6 + 1, 1e6 + 1});
  const auto mesh = render::prepare_tet_mesh(owned.view());
  const auto g = render::gpu::build_gpu_mesh_layout(mesh);
  EXPECT_EQ(g.frame.scale, 2.0);  // the power of two at least the diagonal, sqrt(3)
  for (std::size_t i = 0; i < mesh.points.size(); ++i)
    for (int a = 0; a < 3; ++a)  // exact: offsets of 0, 0.5, 1 from 1e6 + 0.5, halved
      EXPECT_EQ(double(g.points[3 * i + a]), (mesh.points[i][a] - (1e6 + 0.5)) / 2);
}

TEST(GpuMeshLayout, AnyMeshSizeGivesLocalCoordinatesWithinHalfAUnit) {
  for (double size : {1e-30, 1e-12, 1.0, 1e12, 1e30}) {
    auto owned = fixtures::block(fixtures::BlockCells::tets, 2, 2, 2, {-size, 3 * size, 0}, {size, 4 * size, 2 * size});
    const auto mesh = render::prepare_tet_mesh(owned.view());
    const auto g = render::gpu::build_gpu_mesh_layout(mesh);
    EXPECT_GT(g.diagonal, 0.5) << size;
    EXPECT_LE(g.diagonal, 1.0) << size;
    for (float v : g.points) EXPECT_LE(std::fabs(v), 0.5f) << size;
  }
}

TEST(GpuTfLayout, PiecesReproduceTheTransferFunction) {
  render::TransferFunction tf;
  tf.colors = {{990.0, 0.1, 0.2, 0.9}, {1000.0, 0.2, 0.9, 0.3}, {1010.0, 1.0, 0.8, 0.1}};
  tf.opacities = {{995.0, 0.0}, {1000.0, 2.5}, {1000.0, 0.5}, {1005.0, 4.0}};  // a step at 1000
  const auto t = render::gpu::build_gpu_tf_layout(tf);
  const int n = t.breakpoint_count;
  ASSERT_EQ(n, 5);  // 990, 995, 1000, 1005, 1010
  const float* bp = &t.data[(n + 1) * render::gpu::kTfPieceFloats];
  for (double s = 985.0; s <= 1015.0; s += 0.37) {
    int p = 0;
    while (p < n && bp[p] <= static_cast<float>(s)) ++p;
    const float* q = &t.data[p * render::gpu::kTfPieceFloats];
    const double ds = s - q[0];
    EXPECT_NEAR(q[1] + q[2] * ds, tf.extinction(s), 1e-5) << s;
    const Vec3d c = tf.color(s);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(q[4 + i] + q[8 + i] * ds, c[i], 1e-5) << s;
    EXPECT_EQ(q[3] != 0.0f, s < 995.0) << s;  // only below 995 is the extinction zero throughout
  }
}

TEST(GpuTfLayout, ExtinctionIsPerUnitOfTheFrame) {
  // 3e12 per world unit (a nanometre-sized mesh in metres) in a frame 2^-40 world units long:
  // about 2.7 per frame unit, converted in double before float32 holds it.
  render::TransferFunction tf;
  tf.colors = {{0.0, 1.0, 1.0, 1.0}};
  tf.opacities = {{0.0, 3e12}, {1.0, 6e12}};
  const double scale = std::ldexp(1.0, -40);
  const auto t = render::gpu::build_gpu_tf_layout(tf, scale);
  const float* inner = &t.data[render::gpu::kTfPieceFloats];  // the piece [0, 1]
  EXPECT_FLOAT_EQ(inner[1], static_cast<float>(3e12 * scale));
  EXPECT_FLOAT_EQ(inner[2], static_cast<float>(3e12 * scale));
}

TEST(GpuTfLayout, SeriesCoefficientsGiveOneMinusZ) {
  const auto c = render::gpu::one_minus_z_series();
  for (double a : {0.0, 0.01, 0.1, 0.2})
    for (double b : {0.0, 0.02, 0.15, 0.24}) {
      if (a + std::fabs(0.5 * (b - a)) > 0.25 || a + b == 0) continue;
      const double k = 0.5 * (b - a);
      double sum = 0;
      for (int n = 1; n <= 7; ++n)
        for (int j = 0; j <= n; ++j) sum += c[n * 8 + j] * std::pow(a, j) * std::pow(k, n - j);
      // Float coefficients and order 7: ~1e-8 relative to the terms (below float32 resolution).
      EXPECT_NEAR(sum, 1.0 - render::detail::attenuation_integral_general(a, b), 2e-8) << a << " " << b;
    }
}

}  // namespace
}  // namespace penumbra
