// SPDX-License-Identifier: BSD-3-Clause
// A block with a square through-hole: rays through the hole see the background, rays across it
// leave and re-enter the mesh.
#include <gtest/gtest.h>

#include "penumbra/render/image.h"
#include "scenes.h"

namespace penumbra {
namespace {

class Hole : public ::testing::Test {
protected:
  void SetUp() override {
    mesh = test::prepare(fixtures::tet_block_with_hole(6));  // hole: 1/3 < x, y < 2/3, all z
    caster = std::make_unique<render::CpuRayCaster>(mesh);
    scalars.assign(mesh->points.size(), 0.0f);
  }
  std::shared_ptr<const render::TetMesh> mesh;
  std::unique_ptr<render::CpuRayCaster> caster;
  std::vector<float> scalars;
  const render::TransferFunction tf = test::constant_tf(1.5);
};

TEST_F(Hole, RayThroughHoleSeesBackground) {
  for (const Vec3d& o : {Vec3d{0.5, 0.5, -1}, Vec3d{0.4, 0.6, 2}, Vec3d{0.35, 0.64, -3}}) {
    const Vec3d d{0, 0, o.z < 0 ? 1.0 : -1.0};
    const auto r = caster->trace(scalars, tf, {o, d});
    EXPECT_EQ(r.entries, 0);
    EXPECT_EQ(r.segments, 0);
    EXPECT_EQ(r.rgba[3], 0.0);
    const auto ref = render::trace_reference(*mesh, scalars, tf, {o, d});
    EXPECT_EQ(ref.segments, 0);
  }
}

TEST_F(Hole, RayAcrossHoleReentersOnce) {
  // Along x through the hole's middle: 1/3 of solid, 1/3 of hole, 1/3 of solid. At y = 0.5
  // the ray also runs along grid edges (z = 0.5 is a grid plane), stressing the walk.
  for (const Vec3d& o : {Vec3d{-1, 0.5, 0.5}, Vec3d{-1, 0.41, 0.23}}) {
    const auto r = caster->trace(scalars, tf, {o, {1, 0, 0}});
    EXPECT_EQ(r.entries, 2);
    // 1e-12: sums of exactly representable segment end points (see watertight_test.cpp).
    EXPECT_NEAR(r.length_inside, 2.0 / 3.0, 1e-12);
    EXPECT_NEAR(r.optical_depth, 1.5 * 2.0 / 3.0, 1e-12);
    const auto ref = render::trace_reference(*mesh, scalars, tf, {o, {1, 0, 0}});
    EXPECT_EQ(ref.entries, 2);
    EXPECT_NEAR(ref.length_inside, 2.0 / 3.0, 1e-12);
  }
  // Beside the hole, a single entry over the full width.
  const auto r = caster->trace(scalars, tf, {{-1, 0.2, 0.5}, {1, 0, 0}});
  EXPECT_EQ(r.entries, 1);
  EXPECT_NEAR(r.length_inside, 1.0, 1e-12);
}

TEST_F(Hole, ObliqueRayAcrossHoleMatchesReference) {
  const Vec3d o{-0.5, 0.45, 1.2}, d = normalize(Vec3d{1.0, 0.1, -0.6});
  const auto r = caster->trace(scalars, tf, {o, d});
  const auto ref = render::trace_reference(*mesh, scalars, tf, {o, d});
  EXPECT_EQ(r.entries, 2);
  EXPECT_EQ(ref.entries, 2);
  EXPECT_NEAR(r.length_inside, ref.length_inside, 1e-12);
  EXPECT_NEAR(r.optical_depth, ref.optical_depth, 1e-12);
}

TEST_F(Hole, TopViewShowsBackgroundThroughHole) {
  const auto cam = render::Camera::orbit(mesh->bounds, 0, 90, 20, 31, 31);
  const auto img = caster->render(scalars, tf, cam);
  EXPECT_EQ(img.pixel(15, 15)[3], 0.0f);   // centre: through the hole
  EXPECT_GT(img.pixel(15, 9)[3], 0.5f);    // solid rim: 1 - exp(-1.5) = 0.78
}

}  // namespace
}  // namespace penumbra
