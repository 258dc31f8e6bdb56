// SPDX-License-Identifier: BSD-3-Clause
// Watertight traversal: rays exactly through vertices, along edges and in face planes.
#include <gtest/gtest.h>

#include <string>

#include "scenes.h"

namespace penumbra {
namespace {

using fixtures::BlockCells;

// Checks one ray through a homogeneous unit block: the walked length must equal the chord and
// the optical depth sigma * chord. A lost tet segment shortens the length by at least the
// shortest non-zero tet chord these rays see (> 1e-3 here); a doubled one lengthens it as much.
// The tolerances (1e-9 on length, 1e-5 relative on depth as the issue asks) only absorb the
// rounding of a few hundred segment end points.
class Watertight : public ::testing::Test {
protected:
  void SetUp() override {
    mesh = test::prepare(fixtures::block(BlockCells::tets, n, n, n, lo, hi));
    caster = std::make_unique<render::CpuRayCaster>(mesh);
    scalars.assign(mesh->points.size(), 0.5f);
  }
  void check(const Vec3d& o, const Vec3d& dir, const std::string& what) {
    const Vec3d d = normalize(dir);
    const double len = test::chord(lo, hi, o, d);
    const auto r = caster->trace(scalars, test::constant_tf(sigma), {o, d});
    EXPECT_NEAR(r.length_inside, len, 1e-9) << what;
    EXPECT_NEAR(r.optical_depth, sigma * len, 1e-5 * sigma * std::max(len, 1.0)) << what;
    if (len > 0) {
      EXPECT_EQ(r.entries, 1) << what;
      EXPECT_GE(r.segments, 1) << what;
    }
    ++rays;
  }
  static constexpr int n = 4;
  static constexpr double sigma = 2.0;
  const Vec3d lo{0, 0, 0}, hi{1, 1, 1};
  std::shared_ptr<const render::TetMesh> mesh;
  std::unique_ptr<render::CpuRayCaster> caster;
  std::vector<float> scalars;
  int rays = 0;
};

TEST_F(Watertight, AxisRaysAlongGridEdgesAndThroughVertices) {
  // Every interior grid line is a chain of tet edges through grid vertices, lying in two
  // grid face planes: the hardest case for an exit-face rule.
  for (int axis = 0; axis < 3; ++axis)
    for (int i = 1; i < n; ++i)
      for (int j = 1; j < n; ++j)
        for (double sign : {1.0, -1.0}) {
          Vec3d o{}, d{};
          o[axis] = sign > 0 ? -1.0 : 2.0;
          o[(axis + 1) % 3] = static_cast<double>(i) / n;
          o[(axis + 2) % 3] = static_cast<double>(j) / n;
          d[axis] = sign;
          check(o, d, "axis " + std::to_string(axis) + " line " + std::to_string(i) + "," + std::to_string(j));
        }
  EXPECT_EQ(rays, 3 * (n - 1) * (n - 1) * 2);
}

TEST_F(Watertight, RaysInGridFacePlanesAtGenericAngles) {
  // In the plane z = k/n (faces of the cubes' bottom quads) at an angle crossing many edges.
  for (int k = 1; k < n; ++k)
    for (double y0 : {0.1, 0.25, 0.5, 0.63})
      check({-0.5, y0, static_cast<double>(k) / n}, {1.0, 0.37, 0.0}, "plane z=" + std::to_string(k));
  // In the diagonal planes x = y that hold the cubes' interior faces (through the 0-6 diagonal).
  for (double z0 : {0.05, 0.5, 0.77})
    for (double slope : {0.0, 0.3, -0.45})
      check({-0.25, -0.25, z0}, {1.0, 1.0, slope}, "plane x=y z0=" + std::to_string(z0));
}

TEST_F(Watertight, RaysAlongCubeDiagonalsThroughVertices) {
  // The Freudenthal split puts a tet edge on every cube's (1,1,1) diagonal.
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Vec3d start{static_cast<double>(i) / n, static_cast<double>(j) / n, 0.0};
      check(start - Vec3d{1, 1, 1}, {1, 1, 1}, "diagonal from " + std::to_string(i) + "," + std::to_string(j));
      // The other diagonals cross cube faces at vertices but are not tet edges.
      check(start + Vec3d{-1, 1, -1}, {1, -1, 1}, "antidiagonal from " + std::to_string(i) + "," + std::to_string(j));
    }
}

TEST_F(Watertight, RaysThroughSingleVerticesAtOddAngles) {
  for (int i = 1; i < n; ++i)
    for (int j = 1; j < n; ++j)
      for (int k = 1; k < n; ++k) {
        const Vec3d v{static_cast<double>(i) / n, static_cast<double>(j) / n, static_cast<double>(k) / n};
        for (const Vec3d& d : {Vec3d{1, 2, 3}, Vec3d{-3, 1, 2}, Vec3d{2, -1, 0}, Vec3d{1, 1, 0}})
          check(v - d * 4.0, d, "vertex " + std::to_string(i) + std::to_string(j) + std::to_string(k));
      }
}

TEST_F(Watertight, RenderedAxisAlignedViewHasNoCracks) {
  // Looking straight down z at the block centre: the centre pixel's ray runs exactly along the
  // grid line x = y = 0.5, its neighbours close to grid planes. Every pixel inside the block's
  // footprint must see the analytic chord.
  const int size = 33;
  const auto cam = render::Camera::look_at({0.5, 0.5, 20.0}, {0.5, 0.5, 0.5}, {0, 1, 0}, 4.0, size, size);
  render::RenderOptions opts;
  opts.early_termination_opacity = 1.0;
  const auto img = caster->render(scalars, test::constant_tf(sigma), cam, opts);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const auto ray = cam.primary_ray(x, y);
      const double len = test::chord(lo, hi, ray.origin, ray.direction);
      if (len == 0) continue;
      EXPECT_NEAR(img.pixel(x, y)[3], 1.0 - std::exp(-sigma * len), 1e-6) << x << "," << y;
    }
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

TEST(WatertightWelded, DuplicatedInterfacePointsRenderLikeTheSharedMesh) {
  // The same block, but cubes with i >= 2 use their own copies of every point (as solvers do
  // along partition interfaces). The prepared mesh welds them for adjacency, so rays cross the
  // interface x = 0.5 without stopping and the walk reuses projections across different ids.
  const auto shared = fixtures::block(fixtures::BlockCells::tets, 4, 4, 4, {0, 0, 0}, {1, 1, 1});
  auto split = shared;
  const std::size_t np = shared.point_count();
  for (std::size_t i = 0; i < np; ++i) split.add_point(shared.xyz[3 * i], shared.xyz[3 * i + 1], shared.xyz[3 * i + 2]);
  for (std::size_t c = 0; c < split.cell_count(); ++c) {
    double cx = 0;
    for (std::int64_t k = split.offsets[c]; k < split.offsets[c + 1]; ++k) cx += split.xyz[3 * split.connectivity[k]];
    if (cx / 4 > 0.5)
      for (std::int64_t k = split.offsets[c]; k < split.offsets[c + 1]; ++k) split.connectivity[k] += static_cast<std::int64_t>(np);
  }
  const auto a = test::prepare(shared), b = test::prepare(split);
  ASSERT_GT(b->welded_points, 0u);
  render::CpuRayCaster ca(a), cb(b);
  const auto tf = test::constant_tf(1.0);
  const std::vector<float> sa(a->points.size(), 0.0f), sb(b->points.size(), 0.0f);
  for (const render::Ray& ray : {render::Ray{{-1, 0.5, 0.5}, {1, 0, 0}}, render::Ray{{-1, 0.3, 0.7}, normalize(Vec3d{1, 0.2, -0.1})},
                                 render::Ray{{0.5, 0.5, -1}, {0, 0, 1}}}) {
    const auto ra = ca.trace(sa, tf, ray), rb = cb.trace(sb, tf, ray);
    EXPECT_EQ(rb.entries, ra.entries);
    // Same geometry, same walk decisions: identical to rounding of the summed depths.
    EXPECT_NEAR(rb.length_inside, ra.length_inside, 1e-12);
    EXPECT_NEAR(rb.optical_depth, ra.optical_depth, 1e-12);
  }
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

// A bipyramid over the quad A B C D (D raised by 1e-6 out of the plane of A B C): the top two
// tets split the quad along B D, the bottom two along A C, and the sliver tet A B C D (relative
// volume about 1e-6, valid) fills the gap between the two splits. The repaired mesh splits both
// halves along B D and has no sliver; it covers the same region.
fixtures::OwnedMesh bipyramid(bool with_sliver) {
  fixtures::OwnedMesh m;
  const auto a = m.add_point(0, 0, 0), b = m.add_point(1, 0, 0), c = m.add_point(1, 1, 0),
             d = m.add_point(0, 1, 1e-6), top = m.add_point(0.5, 0.5, 1), bottom = m.add_point(0.5, 0.5, -1);
  m.add_cell(10, {top, a, b, d});
  m.add_cell(10, {top, b, c, d});
  if (with_sliver) {
    m.add_cell(10, {bottom, a, b, c});
    m.add_cell(10, {bottom, a, c, d});
    m.add_cell(10, {a, b, c, d});
  } else {
    m.add_cell(10, {bottom, a, b, d});
    m.add_cell(10, {bottom, b, c, d});
  }
  return m;
}

TEST(WatertightSliver, SliverTetRendersLikeTheMeshWithoutIt) {
  const auto with = test::prepare(bipyramid(true)), without = test::prepare(bipyramid(false));
  ASSERT_EQ(with->tets.size(), 5u);
  ASSERT_EQ(without->tets.size(), 4u);
  // A linear field is the same function on both meshes, up to the float rounding of the point
  // values (about 6e-8): where the two meshes split the quad differently, the interpolated
  // scalar differs by that much, the optical depth by at most sigma_max * length * 6e-8, under
  // 1e-6. A lost or doubled segment of these tets (chords of 0.01 or more) changes it by > 1e-3.
  auto field = [](const render::TetMesh& m) {
    std::vector<float> s;
    for (const Vec3d& p : m.points) s.push_back(static_cast<float>(0.3 + 0.4 * p.x + 0.2 * p.y - 0.3 * p.z));
    return s;
  };
  render::TransferFunction tf;
  tf.colors = {{-0.2, 0.1, 0.2, 0.9}, {0.4, 0.2, 0.9, 0.3}, {1.0, 1.0, 0.3, 0.1}};
  tf.opacities = {{-0.2, 1.5}, {0.25, 0.2}, {0.5, 3.0}, {1.0, 0.7}};
  render::RenderOptions opts;
  opts.early_termination_opacity = 1.0;
  const render::CpuRayCaster cw(with), co(without);
  // A ray down through the quad crosses the sliver: one segment more, the same depth.
  const render::Ray down{{0.47, 0.53, 3}, {0, 0, -1}};
  const auto rw = cw.trace(field(*with), tf, down), ro = co.trace(field(*without), tf, down);
  EXPECT_EQ(rw.segments, ro.segments + 1);
  EXPECT_NEAR(rw.optical_depth, ro.optical_depth, 1e-6);
  // Oblique; straight down through the quad (every ray crosses the sliver across its
  // thickness); and from the side in the quad's plane (rays along the sliver).
  for (const auto& cam : {render::Camera::look_at({2.5, -1.7, 1.3}, {0.5, 0.5, 0}, {0, 0, 1}, 40, 40, 40),
                          render::Camera::look_at({0.47, 0.53, 3}, {0.47, 0.53, 0}, {0, 1, 0}, 40, 40, 40),
                          render::Camera::look_at({-2, 0.41, 0}, {0.5, 0.41, 0}, {0, 0, 1}, 40, 40, 40)}) {
    const render::Image iw = cw.render(field(*with), tf, cam, opts), io = co.render(field(*without), tf, cam, opts);
    double worst = 0, alpha = 0;
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        alpha += io.pixel(x, y)[3];
        for (int c = 0; c < 4; ++c)
          worst = std::max(worst, std::fabs(double{iw.pixel(x, y)[c]} - io.pixel(x, y)[c]));
      }
    // The scalar rounding above, plus the float rounding of the pixels themselves.
    EXPECT_LT(worst, 1e-6) << "camera at " << cam.eye.x << ", " << cam.eye.y << ", " << cam.eye.z;
    EXPECT_GT(alpha, 100.0);
  }
}

}  // namespace
}  // namespace penumbra
