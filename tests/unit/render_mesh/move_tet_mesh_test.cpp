// SPDX-License-Identifier: BSD-3-Clause
// A prepared mesh whose points moved (move_tet_mesh, Renderer::move_points): the connectivity's
// work is kept, the picture is that of the moved mesh prepared anew, and motion that inverts or
// flattens a cell is named.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/render/boundary_surface.h"
#include "penumbra/render/camera.h"
#include "penumbra/render/cpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra {
namespace {

using fixtures::BlockCells;

render::TransferFunction ramp() {
  render::TransferFunction tf;
  tf.colors = {{0.0, 0.2, 0.3, 1.0}, {1.0, 1.0, 0.5, 0.1}};
  tf.opacities = {{0.0, 0.5}, {1.0, 4.0}};
  return tf;
}

std::vector<float> radial_field(const render::TetMesh& m) {
  std::vector<float> s;
  for (const auto& p : m.points) s.push_back(static_cast<float>(length(p - Vec3d{0.5, 0.5, 0.5})));
  return s;
}

// Hexes split into tets (the split is what moving keeps), swirled as a vortex moves a Lagrangian mesh.
struct Moved {
  fixtures::OwnedMesh before = fixtures::block(BlockCells::hexes, 6, 5, 4, {0, 0, 0}, {1, 1, 1});
  fixtures::OwnedMesh after = before;
  Moved() { fixtures::swirl(after, {0.5, 0.5, 0}, 0.6, 0.4); }
};

std::vector<unsigned char> rgb8(const render::Image& image) {
  const float white[3] = {1, 1, 1};
  return render::to_rgb8(image, white);
}

render::Camera oblique_camera() {
  return render::Camera::look_at({2.1, -1.3, 1.7}, {0.5, 0.5, 0.5}, {0, 0, 1}, 30.0, 48, 40);
}

TEST(MoveTetMesh, KeepsTheConnectivityAndTakesEverythingElseFromThePoints) {
  Moved s;
  const auto prepared = render::prepare_tet_mesh(s.before.view());
  const auto moved = render::move_tet_mesh(prepared, s.after.view());
  const auto fresh = render::prepare_tet_mesh(s.after.view());
  EXPECT_EQ(moved.tets, fresh.tets);
  EXPECT_EQ(moved.neighbors, fresh.neighbors);
  EXPECT_EQ(moved.source_cell, fresh.source_cell);
  ASSERT_EQ(moved.boundary.size(), fresh.boundary.size());
  EXPECT_EQ(moved.points, fresh.points);
  EXPECT_EQ(moved.bounds.lo, fresh.bounds.lo);
  EXPECT_EQ(moved.bounds.hi, fresh.bounds.hi);
  EXPECT_EQ(moved.frame, fresh.frame);
  EXPECT_DOUBLE_EQ(moved.tet_volume, fresh.tet_volume);
  EXPECT_DOUBLE_EQ(moved.enclosed_volume, fresh.enclosed_volume);
  EXPECT_FALSE(moved.tangled());
  EXPECT_EQ(moved.surface, prepared.surface);  // the boundary's topology, kept
  EXPECT_NE(moved.points, prepared.points);
}

TEST(MoveTetMesh, MovedRendererDrawsTheMeshPreparedAnew) {
  Moved s;
  const auto prepared = std::make_shared<const render::TetMesh>(render::prepare_tet_mesh(s.before.view()));
  const auto moved = std::make_shared<const render::TetMesh>(render::move_tet_mesh(*prepared, s.after.view()));
  const auto fresh = std::make_shared<const render::TetMesh>(render::prepare_tet_mesh(s.after.view()));
  render::CpuRayCaster kept(prepared), rebuilt(fresh);
  kept.move_points(moved);
  const auto scalars = radial_field(*moved);
  render::RenderOptions phong;
  phong.shading.model = render::LightingModel::phong;
  for (const auto& options : {render::RenderOptions{}, phong}) {
    const auto a = kept.render(scalars, ramp(), oblique_camera(), options);
    const auto b = rebuilt.render(scalars, ramp(), oblique_camera(), options);
    EXPECT_EQ(rgb8(a), rgb8(b));
  }
  // Not the picture of the mesh before it moved.
  render::CpuRayCaster before(prepared);
  EXPECT_NE(rgb8(before.render(scalars, ramp(), oblique_camera())), rgb8(kept.render(scalars, ramp(), oblique_camera())));
}

TEST(MoveTetMesh, ARendererRefusesAnotherMesh) {
  Moved s;
  const auto prepared = std::make_shared<const render::TetMesh>(render::prepare_tet_mesh(s.before.view()));
  render::CpuRayCaster caster(prepared);
  EXPECT_THROW(caster.move_points(nullptr), Error);
  const auto other = std::make_shared<const render::TetMesh>(
      render::prepare_tet_mesh(fixtures::block(BlockCells::tets, 3, 3, 3, {0, 0, 0}, {1, 1, 1}).view()));
  try {
    caster.move_points(other);
    ADD_FAILURE() << "expected another mesh to be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not the held mesh's connectivity"), std::string::npos) << e.what();
  }
}

// The first input cell whose signed volume changed sign between `before` and `after`, computed
// from the input cells directly (tets only), independently of the split.
std::int64_t first_inverted_tet_cell(const fixtures::OwnedMesh& before, const fixtures::OwnedMesh& after) {
  auto volume = [](const fixtures::OwnedMesh& m, std::size_t c) {
    Vec3d p[4];
    for (int k = 0; k < 4; ++k) {
      const auto id = static_cast<std::size_t>(m.connectivity[4 * c + static_cast<std::size_t>(k)]);
      p[k] = {m.xyz[3 * id], m.xyz[3 * id + 1], m.xyz[3 * id + 2]};
    }
    return signed_volume6(p[0], p[1], p[2], p[3]);
  };
  for (std::size_t c = 0; c < before.cell_count(); ++c)
    if ((volume(before, c) > 0) != (volume(after, c) > 0)) return static_cast<std::int64_t>(c);
  return -1;
}

TEST(MoveTetMesh, MotionThatInvertsACellNamesIt) {
  const auto before = fixtures::block(BlockCells::tets, 3, 3, 3, {0, 0, 0}, {1, 1, 1});
  auto after = before;
  // An interior point pushed past its neighbours, through the faces of the cells around it.
  const std::size_t p = 1 + 4 * (1 + 4 * 1);
  after.xyz[3 * p] += 0.5;
  const std::int64_t expected = first_inverted_tet_cell(before, after);
  ASSERT_GE(expected, 0);
  const auto prepared = render::prepare_tet_mesh(before.view());
  try {
    render::move_tet_mesh(prepared, after.view(), "pnb_publish_mesh");
    ADD_FAILURE() << "expected the inverted cell to be named";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    const std::string text = e.what();
    EXPECT_NE(text.find("pnb_publish_mesh: cell " + std::to_string(expected) + " is inverted by the points' motion"),
              std::string::npos)
        << text;
  }
}

TEST(MoveTetMesh, MotionThatFlattensACellNamesIt) {
  fixtures::OwnedMesh one;
  for (const Vec3d& p : {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}}) one.add_point(p.x, p.y, p.z);
  one.add_cell(10, {0, 1, 2, 3});
  const auto prepared = render::prepare_tet_mesh(one.view());
  auto flat = one;
  flat.xyz[3 * 3 + 2] = 0;  // the apex lowered into the base's plane
  flat.xyz[3 * 3 + 0] = 0.25;
  flat.xyz[3 * 3 + 1] = 0.25;
  try {
    render::move_tet_mesh(prepared, flat.view());
    ADD_FAILURE() << "expected the flattened cell to be named";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cell 0 is flattened"), std::string::npos) << e.what();
  }
}

TEST(MoveTetMesh, NonFiniteOrOutOfRangePointsAreNamed) {
  Moved s;
  const auto prepared = render::prepare_tet_mesh(s.before.view());
  auto bad = s.after;
  bad.xyz[3 * 7 + 1] = std::nan("");
  try {
    render::move_tet_mesh(prepared, bad.view());
    ADD_FAILURE() << "expected the NaN coordinate to be named";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("point 7 has a NaN"), std::string::npos) << e.what();
  }
  auto far = s.after;
  for (std::size_t i = 0; i < far.point_count(); ++i) far.xyz[3 * i] += 1e12;
  EXPECT_THROW(render::move_tet_mesh(prepared, far.view()), Error);
}

TEST(MoveTetMesh, WeldsHoldWhileDuplicatedPointsMoveTogether) {
  const auto mesh = fixtures::two_blocks_with_duplicated_interface();
  const auto prepared = render::prepare_tet_mesh(mesh.view());
  ASSERT_EQ(prepared.welds.size(), 9u);
  auto together = mesh;
  fixtures::swirl(together, {1, 0.5, 0}, 0.8, 0.3);
  EXPECT_TRUE(render::keeps_welds(prepared, together.view()));
  const auto moved = render::move_tet_mesh(prepared, together.view());
  EXPECT_EQ(moved.boundary.size(), prepared.boundary.size());  // still no false boundary at the interface
  auto apart = together;
  const auto copy = static_cast<std::size_t>(prepared.welds[0][0]);
  apart.xyz[3 * copy] += 1e-3;  // one copy of an interface point drifts from its twin
  EXPECT_FALSE(render::keeps_welds(prepared, apart.view()));
}

}  // namespace
}  // namespace penumbra
