// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/render_mesh/tet_mesh_test.cpp -- splitting, orientation, welding, adjacency
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/render/boundary_surface.h"
#include "penumbra/render/tet_mesh.h"

using namespace penumbra;
using fixtures::BlockCells;

namespace {

double total_volume(const render::TetMesh& m) {
  double v = 0;
  for (const auto& t : m.tets) v += signed_volume6(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]) / 6;
  return v;
}

// Renumbers points randomly so the smallest-id diagonal rule meets every configuration.
fixtures::OwnedMesh shuffled(const fixtures::OwnedMesh& in, unsigned seed) {
  std::vector<std::int64_t> perm(in.point_count());
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(seed));
  fixtures::OwnedMesh out = in;
  for (std::size_t i = 0; i < perm.size(); ++i)
    for (int c = 0; c < 3; ++c) out.xyz[3 * perm[i] + c] = in.xyz[3 * i + c];
  for (auto& id : out.connectivity) id = perm[static_cast<std::size_t>(id)];
  return out;
}

void expect_conforming(const render::TetMesh& m, std::size_t expected_boundary_triangles, double expected_volume) {
  // Every face either has exactly one neighbour, which points back, or is on the boundary.
  for (std::size_t t = 0; t < m.tets.size(); ++t) {
    ASSERT_GT(signed_volume6(m.points[m.tets[t][0]], m.points[m.tets[t][1]], m.points[m.tets[t][2]],
                             m.points[m.tets[t][3]]), 0.0) << "tet " << t;
    for (int f = 0; f < 4; ++f) {
      const std::int32_t n = m.neighbors[t][f];
      if (n < 0) continue;
      const auto& back = m.neighbors[static_cast<std::size_t>(n)];
      ASSERT_EQ(std::count(back.begin(), back.end(), static_cast<std::int32_t>(t)), 1) << "tet " << t << " face " << f;
    }
  }
  EXPECT_EQ(m.boundary.size(), expected_boundary_triangles);
  EXPECT_NEAR(total_volume(m), expected_volume, 1e-12 * expected_volume * m.tets.size());
  EXPECT_TRUE(m.surface->is_closed());
}

}  // namespace

TEST(TetMesh, ConformingSplitOfEveryCellKindUnderAnyNumbering) {
  const int n = 4;
  // The boundary of an n^3 block is 6 n^2 squares, two triangles each, whatever the cells.
  const std::size_t boundary = 12 * n * n;
  for (auto kind : {BlockCells::tets, BlockCells::hexes, BlockCells::wedges, BlockCells::pyramids})
    for (unsigned seed : {0u, 1u, 2u, 3u, 4u}) {
      SCOPED_TRACE("kind " + std::to_string(int(kind)) + " seed " + std::to_string(seed));
      const auto mesh = seed == 0 ? fixtures::block(kind, n, n, n, {0, 0, 0}, {2, 1, 1})
                                  : shuffled(fixtures::block(kind, n, n, n, {0, 0, 0}, {2, 1, 1}), seed);
      const auto m = render::prepare_tet_mesh(mesh.view());
      expect_conforming(m, boundary, 2.0);
      const std::size_t per_cell = kind == BlockCells::tets ? 6 : kind == BlockCells::hexes ? 6
                                   : kind == BlockCells::wedges ? 6 : 12;  // tets per cube
      EXPECT_EQ(m.tets.size(), per_cell * n * n * n);
    }
}

TEST(TetMesh, InvertedTetsAreReoriented) {
  auto mesh = fixtures::block(BlockCells::tets, 2, 2, 2, {0, 0, 0}, {1, 1, 1});
  for (std::size_t c = 0; c < mesh.cell_count(); c += 3) std::swap(mesh.connectivity[4 * c], mesh.connectivity[4 * c + 1]);
  const auto m = render::prepare_tet_mesh(mesh.view());
  EXPECT_EQ(m.reoriented_tets, (mesh.cell_count() + 2) / 3);
  expect_conforming(m, 12 * 4, 1.0);
}

TEST(TetMesh, AFoldedMeshIsTangledAndABlockIsNot) {
  for (auto kind : {fixtures::BlockCells::tets, fixtures::BlockCells::hexes, fixtures::BlockCells::wedges,
                    fixtures::BlockCells::pyramids}) {
    const auto block = render::prepare_tet_mesh(fixtures::block(kind, 3, 2, 2, {5, 0, 0}, {6, 2, 1}).view());
    EXPECT_NEAR(block.tet_volume, 2.0, 1e-12);
    EXPECT_NEAR(block.enclosed_volume, 2.0, 1e-12);
    EXPECT_FALSE(block.tangled());
  }
  // Two tets on the same side of the face they share: the second folds back over the first.
  fixtures::OwnedMesh folded;
  const auto a = folded.add_point(0, 0, 0), b = folded.add_point(1, 0, 0), c = folded.add_point(0, 1, 0);
  const auto top = folded.add_point(0.2, 0.2, 1), fold = folded.add_point(0.3, 0.3, 0.5);
  folded.add_cell(10, {a, b, c, top});
  folded.add_cell(10, {a, c, b, fold});  // inverted as given: reoriented, and then on top's side
  const auto m = render::prepare_tet_mesh(folded.view());
  EXPECT_EQ(m.reoriented_tets, 1u);
  EXPECT_TRUE(m.tangled()) << m.tet_volume << " vs " << m.enclosed_volume;
}

TEST(TetMesh, DuplicatedInterfacePointsAreWelded) {
  const auto left = fixtures::two_blocks_with_duplicated_interface();
  const auto base = static_cast<std::int64_t>(left.point_count() / 2);  // the second block's first point
  const auto m = render::prepare_tet_mesh(left.view());
  EXPECT_EQ(m.welded_points, 9u);  // the 3x3 points of the shared plane
  // Welded, the two blocks form one 2x1x1 box: no false boundary at x = 1.
  // 4x2x2 unit squares of size 1/2: 2*(2*2) + 2*(4*2) + 2*(4*2) = 40 squares, 80 triangles.
  const std::size_t boundary = 80;
  expect_conforming(m, boundary, 2.0);
  for (const auto& bf : m.boundary) {
    const auto& t = m.tets[static_cast<std::size_t>(bf.tet)];
    int on_plane = 0;
    for (int k = 0; k < 4; ++k)
      if (k != bf.face && m.points[t[k]].x == 1.0) ++on_plane;
    EXPECT_LT(on_plane, 3) << "false internal boundary face at x = 1";
  }
  // Tets still carry the caller's own ids, so per-point fields stay discontinuous if they are.
  std::size_t uses_copy = 0;
  for (const auto& t : m.tets)
    for (auto id : t) uses_copy += id >= base ? 1 : 0;
  EXPECT_GT(uses_copy, 0u);
}

TEST(TetMesh, SurfaceOfMeshWithHoleIsATorus) {
  const auto mesh = fixtures::tet_block_with_hole(6);
  const auto m = render::prepare_tet_mesh(mesh.view());
  EXPECT_EQ(m.surface->component_count(), 1u);
  EXPECT_EQ(m.surface->euler_characteristic(), 0);  // genus one: one through-hole
  EXPECT_TRUE(m.surface->is_closed());
  EXPECT_NEAR(m.surface->area(), 6.0 - 2 * (1.0 / 9) + 4 * (1.0 / 3), 1e-5);
}

TEST(TetMesh, CollapsedHexBecomesTheWedgeItIs) {
  // A hex whose top face collapsed onto an edge (repeated ids), as some exporters write wedges.
  fixtures::OwnedMesh mesh;
  for (double z : {0.0, 1.0})
    for (auto [x, y] : {std::pair{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}}) mesh.add_point(x, y, z);
  mesh.add_cell(12, {0, 1, 2, 3, 4, 5, 5, 4});
  const auto m = render::prepare_tet_mesh(mesh.view());
  EXPECT_NEAR(total_volume(m), 0.5, 1e-12);
  EXPECT_TRUE(m.surface->is_closed());
}

TEST(TetMesh, OverlappingCellsAreRejected) {
  fixtures::OwnedMesh mesh;
  for (auto p : {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}, Vec3d{0, 0, -1}, Vec3d{0.1, 0.1, 2}})
    mesh.add_point(p.x, p.y, p.z);
  mesh.add_cell(10, {0, 1, 2, 3});
  mesh.add_cell(10, {0, 1, 2, 4});
  mesh.add_cell(10, {0, 1, 2, 5});  // a third cell on face (0,1,2)
  try {
    render::prepare_tet_mesh(mesh.view(), "pnb_publish_mesh");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cells 0, 1, 2"), std::string::npos) << e.what();
  }
}

TEST(TetMesh, ValidationErrorsNameTheCall) {
  auto mesh = fixtures::block(BlockCells::tets, 1, 1, 1, {0, 0, 0}, {1, 1, 1});
  mesh.connectivity[5] = 100;
  try {
    render::prepare_tet_mesh(mesh.view(), "pnb_publish_mesh");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("pnb_publish_mesh: cell 1 references point 100", 0), 0u) << e.what();
  }
}
