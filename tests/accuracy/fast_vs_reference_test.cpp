// SPDX-License-Identifier: BSD-3-Clause
// The fast renderer against the double-precision reference on smooth fields.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "penumbra/render/image.h"
#include "scenes.h"

namespace penumbra {
namespace {

using fixtures::BlockCells;

// A multi-point transfer function with a transparent band, colour points apart from opacity
// points, and a slope steep enough that tets straddle several breakpoints.
render::TransferFunction multi_point_tf() {
  render::TransferFunction tf;
  tf.colors = {{-1.0, 0.1, 0.2, 0.9}, {0.0, 0.2, 0.9, 0.3}, {0.6, 1.0, 0.8, 0.1}, {1.2, 0.9, 0.1, 0.1}};
  tf.opacities = {{-0.8, 0.0}, {-0.3, 2.5}, {0.1, 0.0}, {0.2, 0.0}, {0.5, 4.0}, {1.0, 1.0}};
  return tf;
}

double smooth_field(double x, double y, double z) {
  return std::sin(2.1 * x + 0.3) * std::cos(1.7 * y - 0.2) + 0.4 * z * z - 0.2;
}

struct Case {
  std::string name;
  fixtures::OwnedMesh mesh;
};

void compare(const Case& c) {
  const auto mesh = test::prepare(c.mesh);
  render::CpuRayCaster caster(mesh);
  const auto field = fixtures::sample(c.mesh, smooth_field);
  const std::vector<float> scalars(field.begin(), field.end());
  const auto tf = multi_point_tf();
  const auto cam = render::Camera::orbit(mesh->bounds, 33, 21, 30, 48, 48);
  render::RenderOptions opts;
  opts.early_termination_opacity = 1.0;  // the reference integrates every ray to the end
  const auto fast = caster.render(scalars, tf, cam, opts);
  const auto ref = render::render_reference(*mesh, scalars, tf, cam);
  double max_diff = 0;
  int covered = 0;
  for (std::size_t i = 0; i < fast.rgba.size(); ++i) max_diff = std::max(max_diff, double(std::fabs(fast.rgba[i] - ref.rgba[i])));
  for (std::size_t i = 3; i < ref.rgba.size(); i += 4) covered += ref.rgba[i] > 0.05f;
  // The closed form and the quadrature agree to ~1e-10 per ray; the images hold floats, so
  // 2e-6 is float rounding of values up to ~2 plus margin. Any traversal error (a lost or
  // doubled tet) changes a pixel by > 1e-3.
  EXPECT_LT(max_diff, 2e-6) << c.name;
  const float background[3] = {0, 0, 0};
  const double rms = render::rms_difference_pct(render::to_rgb8(fast, background), render::to_rgb8(ref, background));
  // At most rare 1-step rounding flips of the 8-bit conversion: far below one step (0.39 %).
  EXPECT_LT(rms, 0.05) << c.name;
  EXPECT_GT(covered, 200) << c.name << ": the scene must actually show the volume";
}

TEST(FastVsReference, TetBlock) {
  compare({"tet block", fixtures::block(BlockCells::tets, 7, 6, 5, {-1, -1, -1}, {1, 1, 1})});
}

TEST(FastVsReference, HexBlockSplitIntoTets) {
  compare({"hex block", fixtures::block(BlockCells::hexes, 6, 6, 6, {-1, -1, -1}, {1, 1, 1})});
}

TEST(FastVsReference, MeshWithHole) {
  auto m = fixtures::tet_block_with_hole(9);
  for (std::size_t i = 0; i < m.xyz.size(); ++i) m.xyz[i] = 2.0 * m.xyz[i] - 1.0;  // field's interesting range
  compare({"holed block", std::move(m)});
}

TEST(FastVsReference, SingleRaysAgreeTightly) {
  const auto owned = fixtures::block(BlockCells::tets, 5, 5, 5, {-1, -1, -1}, {1, 1, 1});
  const auto mesh = test::prepare(owned);
  render::CpuRayCaster caster(mesh);
  const auto field = fixtures::sample(owned, smooth_field);
  const std::vector<float> scalars(field.begin(), field.end());
  const auto tf = multi_point_tf();
  const Vec3d origins[] = {{-3, 0.1, 0.2}, {0.3, -2.5, 1.7}, {2, 2, 2}};
  for (const Vec3d& o : origins) {
    const Vec3d d = normalize(Vec3d{0.05, -0.02, 0.1} - o);
    const auto a = caster.trace(scalars, tf, {o, d});
    const auto b = render::trace_reference(*mesh, scalars, tf, {o, d});
    // Closed form vs adaptive quadrature (1e-10 relative): 1e-9 absolute on values <= ~3.
    EXPECT_NEAR(a.optical_depth, b.optical_depth, 1e-9);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(a.rgba[c], b.rgba[c], 1e-9) << "channel " << c;
    EXPECT_NEAR(a.length_inside, b.length_inside, 1e-12);
    EXPECT_EQ(a.segments, b.segments);
    EXPECT_GT(a.optical_depth, 0.1);
  }
}

TEST(FastVsReference, JitteredMeshManyRaysThroughVerticesAndGenericPoints) {
  // Interior points moved by up to 0.2 cells: faces in general position, no two tets alike.
  auto owned = fixtures::block(BlockCells::tets, 6, 5, 4, {0, 0, 0}, {1.2, 1.0, 0.8});
  std::uint64_t state = 12345;
  auto rnd = [&] {  // deterministic LCG in [-1, 1)
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) / 4503599627370496.0 - 1.0;
  };
  for (std::size_t i = 0; i < owned.point_count(); ++i) {
    double* p = &owned.xyz[3 * i];
    const bool interior = p[0] > 1e-9 && p[0] < 1.2 - 1e-9 && p[1] > 1e-9 && p[1] < 1 - 1e-9 && p[2] > 1e-9 && p[2] < 0.8 - 1e-9;
    if (interior)
      for (int a = 0; a < 3; ++a) p[a] += 0.2 * 0.2 * rnd();
  }
  const auto mesh = test::prepare(owned);
  render::CpuRayCaster caster(mesh);
  const std::vector<float> scalars(mesh->points.size(), 0.0f);
  const auto tf = test::constant_tf(1.0);
  int rays = 0;
  for (std::size_t i = 0; i < mesh->points.size(); i += 7) {
    // One ray aimed exactly at a mesh point (through a vertex, up to the rounding of the
    // direction) and one at a generic point.
    const Vec3d o{-1.0 + 0.1 * rnd(), 0.5 + rnd(), 0.4 + rnd()};
    for (const Vec3d& target : {mesh->points[i], mesh->points[i] + Vec3d{0.013, -0.007, 0.005}}) {
      const Vec3d d = normalize(target - o);
      const auto a = caster.trace(scalars, tf, {o, d});
      const auto b = render::trace_reference(*mesh, scalars, tf, {o, d});
      // Both sum exact segment lengths; only rounding (~1e-15 per segment) separates them,
      // while one lost or doubled tet would differ by at least its chord (> 1e-4 here).
      EXPECT_NEAR(a.length_inside, b.length_inside, 1e-10) << "point " << i;
      EXPECT_NEAR(a.optical_depth, b.optical_depth, 1e-10) << "point " << i;
      // A ray aimed at a boundary point may graze the surface: entry counts are compared for
      // targets inside only.
      const Vec3d c = target;
      if (c.x > 0.01 && c.x < 1.19 && c.y > 0.01 && c.y < 0.99 && c.z > 0.01 && c.z < 0.79)
        EXPECT_EQ(a.entries, b.entries) << "point " << i;
      ++rays;
    }
  }
  EXPECT_GT(rays, 50);
}

}  // namespace
}  // namespace penumbra
