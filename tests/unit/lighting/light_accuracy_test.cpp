// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/lighting/light_accuracy_test.cpp -- the light volume against analytic transmittance
// and the double-precision reference
#include <gtest/gtest.h>

#include <cmath>

#include "lighting_test_util.h"

namespace penumbra::lighting_test {
namespace {

// A light volume on `mesh` for field s through tf and `lights`, solved to convergence.
LightVolume converged_volume(const std::shared_ptr<const TetMesh>& mesh, const LightVolumeOptions& opt,
                             const std::vector<float>& s, const TransferFunction& tf, std::vector<Light> lights) {
  LightVolume lv(mesh, opt);
  lv.set_field(s, tf);
  lv.set_lights(std::move(lights));
  EXPECT_TRUE(lv.update().converged);
  return lv;
}

// Homogeneous slab [0,2]x[0,1]^2, tau = 1.5, light along +x: rho = exp(-1.5 x) exactly. The
// level-0 sweep is exact for a grid-aligned light (exponential fitting) and every level-1 step
// integrates a constant tau exactly, so only float storage (1e-7) remains.
TEST(LightAccuracy, HomogeneousSlabAlongAxisIsBeerLambert) {
  const auto mesh = tet_block(16, 6, 6, {0, 0, 0}, {2, 1, 1});
  LightVolumeOptions opt;
  opt.level0_resolution = 33;
  LightVolume lv(mesh, opt);
  const auto tf = constant_tf(1.5);
  lv.set_field(field(*mesh, [](const Vec3d&) { return 0.0; }), tf);
  lv.set_lights({directional({1, 0, 0})});
  const auto r = lv.update();
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.lost_traces, 0u);
  const double worst = max_error_vs(lv.light_rho(0), *mesh, [](const Vec3d& x) { return std::exp(-1.5 * x.x); });
  double worst0 = 0;
  const auto& rho0 = lv.level0_rho(0);
  const auto view = lv.level0();
  for (int i = 0; i < view.dims[0]; ++i) {
    const double want = std::exp(-1.5 * (view.lo.x + i * view.spacing.x));
    worst0 = std::max(worst0, std::fabs(rho0[static_cast<std::size_t>(i + view.dims[0] * (3 + view.dims[1] * 4))] - want));
  }
  EXPECT_LT(worst, 2e-6);
  EXPECT_LT(worst0, 2e-6);
}

// Oblique light through the slab: the rays enter through three different faces, so rho has
// kinks along the characteristics from the slab's edges. Level 1 interpolates the mean
// extinction along the ray, which is constant here, so it stays exact to float rounding.
TEST(LightAccuracy, HomogeneousSlabObliqueMatchesReference) {
  const auto mesh = tet_block(16, 8, 8, {0, 0, 0}, {2, 1, 1});
  const auto tf = constant_tf(1.5);
  const auto s = field(*mesh, [](const Vec3d&) { return 0.0; });
  const Light light = directional({1, 0.4, 0.25});
  LightVolumeOptions opt;
  opt.level0_resolution = 33;
  const LightVolume lv = converged_volume(mesh, opt, s, tf, {light});
  const double err = max_error_vs_reference(lv, 0, mesh, s, tf, light);
  std::printf("oblique slab: max |rho - reference| = %.3g\n", err);
  EXPECT_LT(err, 1e-6);
}

// A light along a face diagonal of a structured block: every ray runs along mesh edges and in
// the planes of faces, the top and bottom boundary faces included, and the projected edge values
// are rounding noise instead of zeros. Those walks are retried with the noise snapped (and the
// boundary rays pushed inside), so every vertex, on the boundary too, gets Beer-Lambert along
// its own ray, as with a generic direction.
TEST(LightAccuracy, DiagonalLightAlongBoundaryFaces) {
  const auto mesh = tet_block(8, 8, 4, {0, 0, 0}, {1, 1, 0.5});
  const auto tf = constant_tf(1.2);
  const auto s = field(*mesh, [](const Vec3d&) { return 0.0; });
  const Light light = directional({1, 1, 0});
  LightVolumeOptions opt;
  opt.level0_resolution = 17;
  const LightVolume lv = converged_volume(mesh, opt, s, tf, {light});
  // The ray from x back towards the light leaves the block through x = 0 or y = 0.
  const double err = max_error_vs(lv.light_rho(0), *mesh,
                                  [](const Vec3d& x) { return std::exp(-1.2 * std::sqrt(2.0) * std::min(x.x, x.y)); });
  std::printf("diagonal light: max |rho - exp(-tau d)| = %.3g\n", err);
  EXPECT_LT(err, 2e-6);
}

// The converged light does not depend on c dt (the level-1 step h): with the attenuation
// defined as sigma_a * tau per unit length, steps of 0.25x, 1x, 4x and 10x the default all
// converge to Beer-Lambert. In a homogeneous medium the interpolation is exact, so they agree to
// float rounding; in a heterogeneous one they agree with the reference to the interpolation
// error, which shrinks as the step grows (fewer re-interpolations along each characteristic).
TEST(LightAccuracy, ConvergedLightIndependentOfStep) {
  const auto mesh = tet_block(12, 8, 8, {0, 0, 0}, {1.5, 1, 1});
  const Light light = directional({1, 0.5, -0.7});
  const auto homogeneous = field(*mesh, [](const Vec3d&) { return 0.7; });
  const auto varying = field(*mesh, [](const Vec3d& p) { return 0.5 + 0.4 * std::sin(3 * p.x + 2 * p.y) * p.z; });
  const auto tf = ramp_tf(2.0);
  double previous_rms = HUGE_VAL;
  for (double scale : {0.25, 1.0, 4.0, 10.0}) {
    LightVolumeOptions opt;
    opt.level0_resolution = 24;
    LightVolume probe(mesh, opt);
    opt.level1_step = scale * probe.level1_step();
    opt.level1_adaptive_step = false;  // every vertex takes exactly this step
    opt.propagation_tolerance = 1e-5;
    for (const auto* s : {&homogeneous, &varying}) {
      LightVolume lv(mesh, opt);
      lv.set_field(*s, tf);
      lv.set_lights({light});
      const auto report = lv.update();
      EXPECT_TRUE(report.converged);
      const render::LightTransmittanceReference ref(mesh);
      double worst = 0, sq = 0;
      for (std::size_t p = 0; p < mesh->points.size(); ++p) {
        const double e = lv.light_rho(0)[p] - ref.transmittance(*s, tf, 1.0, light, mesh->points[p]);
        worst = std::max(worst, std::fabs(e));
        sq += e * e;
      }
      const double rms = std::sqrt(sq / static_cast<double>(mesh->points.size()));
      std::printf("step %5.2fx (%d passes) %s: max error %.3g, rms %.3g\n", scale, report.level1_passes,
                  s == &homogeneous ? "homogeneous" : "varying    ", worst, rms);
      if (s == &homogeneous) {
        // Float rounding, or at 0.25x (dozens of slowly contracting passes) about ten times the
        // per-pass tolerance.
        EXPECT_LT(worst, 1e-4);
      } else {
        EXPECT_LT(rms, 0.03);
        EXPECT_LT(worst, 0.12);
        EXPECT_LT(rms, previous_rms * 1.05);  // no worse with longer steps
        previous_rms = rms;
      }
    }
  }
}

// A box occluder in a homogeneous medium: points whose ray to the light crosses the box are
// exactly 0 (level 1 tests every trace-back segment against the box), the rest follow
// Beer-Lambert; only the one-edge-wide penumbra band (interpolation across the shadow edge) is
// left out of the exact comparison.
TEST(LightAccuracy, BoxOccluderCastsShadow) {
  const auto mesh = tet_block(10, 10, 10, {0, 0, 0}, {1, 1, 1});
  const auto tf = constant_tf(0.8);
  const auto s = field(*mesh, [](const Vec3d&) { return 0.0; });
  LightVolumeOptions opt;
  opt.level0_resolution = 32;
  opt.occluders = {Bounds{{0.35, 0.35, 0.2}, {0.65, 0.65, 0.4}}};
  const LightVolume lv = converged_volume(mesh, opt, s, tf, {directional({0, 0, 1})});
  int shadowed = 0, lit = 0;
  for (std::size_t p = 0; p < mesh->points.size(); ++p) {
    const Vec3d& x = mesh->points[p];
    const bool under = x.x >= 0.35 && x.x <= 0.65 && x.y >= 0.35 && x.y <= 0.65;
    const bool clear = x.x < 0.25 || x.x > 0.75 || x.y < 0.25 || x.y > 0.75;
    if (under && x.z >= 0.2) {
      EXPECT_EQ(lv.light_rho(0)[p], 0.0f) << "point " << p;
      ++shadowed;
    } else if (clear || x.z < 0.2) {
      EXPECT_NEAR(lv.light_rho(0)[p], std::exp(-0.8 * x.z), 1e-5) << "point " << p;
      ++lit;
    }
  }
  EXPECT_GT(shadowed, 20);
  EXPECT_GT(lit, 500);
  // The level-0 mask marks the box.
  const auto view = lv.level0();
  int occluder_nodes = 0;
  for (auto m : *view.mask) occluder_nodes += m == render::Level0Mask::occluder;
  EXPECT_GT(occluder_nodes, 0);
}

// A square through-hole along z in the middle third: light along +x crosses the hole without
// attenuation, so behind it rho = exp(-tau (x - 1/3)) instead of exp(-tau x). Level 0 carries
// the light across (empty nodes), level 1 picks it up where the trace leaves the mesh from the
// empty nodes around the exit point, which are exact here (the hole's axis is grid-aligned).
TEST(LightAccuracy, LightCrossesHole) {
  const auto mesh = prepare(fixtures::tet_block_with_hole(12));
  const auto tf = constant_tf(2.0);
  const auto s = field(*mesh, [](const Vec3d&) { return 0.0; });
  LightVolumeOptions opt;
  opt.level0_resolution = 33;
  const Light light = directional({1, 0, 0});
  const LightVolume lv = converged_volume(mesh, opt, s, tf, {light});
  int behind = 0;
  const auto used = used_points(*mesh);
  for (std::size_t p = 0; p < mesh->points.size(); ++p) {
    const Vec3d& x = mesh->points[p];
    if (used[p] && x.y > 0.34 && x.y < 0.66 && x.x >= 2.0 / 3 - 1e-9) {
      EXPECT_NEAR(lv.light_rho(0)[p], std::exp(-2.0 * (x.x - 1.0 / 3)), 0.01) << "point " << p;
      ++behind;
    }
  }
  EXPECT_GT(behind, 10);
  // Vertices whose ray runs exactly along a boundary face (the hole's walls y = 1/3, 2/3 and
  // the outer faces) are lit or not depending on which side of the face one looks from; the
  // reference and the solver may pick different sides, so they are left out.
  auto on_plane = [](double v) {
    for (double c : {0.0, 1.0 / 3, 2.0 / 3, 1.0})
      if (std::fabs(v - c) < 1e-9) return true;
    return false;
  };
  const double err = max_error_vs_reference(lv, 0, mesh, s, tf, light, [&](const Vec3d& x) {
    return !on_plane(x.y) && !on_plane(x.z);
  });
  // Level 0 resamples the walls at its nodes: the segment between the last node in a wall and
  // the first in the hole is attenuated by the trapezoid of their extinctions, which misplaces
  // the wall by up to half a level-0 cell: |error| <= rho * tau * h0 / 2 = 0.5 * 2 / 32 / 2 ~ 1.6 %.
  std::printf("hole: max |rho - reference| = %.3g\n", err);
  EXPECT_LT(err, 0.016);
}

// A point light inside a cell (not at a vertex) of a homogeneous block: rho = exp(-tau |x - P|)
// (no 1/r^2 fall-off, eq. 4). The mean extinction along the ray is constant, so the radial
// traces are exact up to float rounding.
TEST(LightAccuracy, PointLightInsideCell) {
  const auto mesh = tet_block(10, 10, 10, {0, 0, 0}, {1, 1, 1});
  const auto tf = constant_tf(1.0);
  const auto s = field(*mesh, [](const Vec3d&) { return 0.0; });
  const Vec3d P{0.437, 0.512, 0.463};
  LightVolumeOptions opt;
  opt.level0_resolution = 24;
  const LightVolume lv = converged_volume(mesh, opt, s, tf, {point_light(P)});
  const double worst = max_error_vs(lv.light_rho(0), *mesh, [&](const Vec3d& x) { return std::exp(-length(x - P)); });
  std::printf("point light: max |rho - exp(-r)| = %.3g\n", worst);
  EXPECT_LT(worst, 1e-5);
  // The reference agrees with the analytic value to rounding.
  const render::LightTransmittanceReference ref(mesh);
  EXPECT_NEAR(ref.transmittance(s, tf, 1.0, point_light(P), {0.9, 0.1, 0.3}), std::exp(-length(Vec3d{0.9, 0.1, 0.3} - P)), 1e-12);
}

}  // namespace
}  // namespace penumbra::lighting_test
