// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/lighting/light_scattering_test.cpp -- eq. 9 (combining lights) and eq. 12 (diffusion)
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <iostream>

#include "lighting/level1_mesh.h"
#include "lighting/light_scattering.h"
#include "lighting_test_util.h"

namespace penumbra::lighting_test {
namespace {

struct Scene {
  std::shared_ptr<const TetMesh> mesh = tet_block(8, 8, 8, {0, 0, 0}, {1, 1, 1});
  TransferFunction tf = ramp_tf(3.0);
  std::vector<float> s = field(*mesh, [](const Vec3d& p) { return 0.5 + 0.5 * std::sin(4 * p.x) * std::cos(3 * p.y + p.z); });
};

std::vector<float> solve(const Scene& sc, std::vector<Light> lights, std::array<double, 3> sigma_s,
                         const render::LightBudget& budget = {}) {
  LightVolumeOptions opt;
  opt.level0_resolution = 16;
  opt.sigma_s = sigma_s;
  opt.scatter_tolerance = 1e-7;
  LightVolume lv(sc.mesh, opt);
  lv.set_field(sc.s, sc.tf);
  lv.set_lights(std::move(lights));
  for (int frame = 0; frame < 10000; ++frame)
    if (lv.update(budget).converged) return lv.light_rgb();
  ADD_FAILURE() << "did not converge";
  return lv.light_rgb();
}

// Eq. 9 and 12 are linear in the lights: L(l1 + l2) = L(l1) + L(l2), per channel, to the
// scattering tolerance (1e-7 relative per iteration).
TEST(LightScattering, LinearInTheLights) {
  const Scene sc;
  const Light a = directional({1, 0.3, -0.2}, {1.0, 0.5, 0.2});
  const Light b = point_light({0.3, 1.4, 0.6}, {0.1, 0.4, 0.9});
  const auto la = solve(sc, {a}, {0.5, 1.0, 2.0});
  const auto lb = solve(sc, {b}, {0.5, 1.0, 2.0});
  const auto lab = solve(sc, {a, b}, {0.5, 1.0, 2.0});
  double worst = 0;
  for (std::size_t i = 0; i < lab.size(); ++i) worst = std::max(worst, static_cast<double>(std::fabs(lab[i] - la[i] - lb[i])));
  EXPECT_LT(worst, 1e-4);
}

// The blur depends on sigma_s, not on how the iterations are spread over frames: one iteration
// per frame converges to the same field as an unlimited budget.
TEST(LightScattering, BlurIndependentOfIterationBudget) {
  const Scene sc;
  const Light a = directional({0.2, 1, 0.4});
  const auto all_at_once = solve(sc, {a}, {1, 1, 1});
  render::LightBudget one;
  one.max_work_units = 1;
  const auto one_per_frame = solve(sc, {a}, {1, 1, 1}, one);
  double worst = 0;
  for (std::size_t i = 0; i < all_at_once.size(); ++i)
    worst = std::max(worst, static_cast<double>(std::fabs(all_at_once[i] - one_per_frame[i])));
  EXPECT_LT(worst, 1e-5);
  // ... and more scattering blurs more: the field's spread shrinks as sigma_s grows.
  auto spread = [](const std::vector<float>& rgb) {
    float lo = 1e30f, hi = -1e30f;
    for (std::size_t i = 0; i < rgb.size(); i += 3) {
      lo = std::min(lo, rgb[i]);
      hi = std::max(hi, rgb[i]);
    }
    return hi - lo;
  };
  const auto none = solve(sc, {a}, {0, 0, 0});
  const auto strong = solve(sc, {a}, {10, 10, 10});
  EXPECT_GT(spread(none), spread(all_at_once));
  EXPECT_GT(spread(all_at_once), spread(strong));
}

// A constant field stays constant, and the diffusion adds no new extrema: the result lies within
// the range of the unscattered field, channel by channel.
TEST(LightScattering, ConstantsStayAndNoNewExtrema) {
  const Scene sc;
  LightVolumeOptions opt;
  opt.level0_resolution = 16;
  opt.sigma_a = 0;  // no absorption: rho = 1 everywhere
  opt.sigma_s = {3, 3, 3};
  opt.scatter_tolerance = 1e-7;
  LightVolume lv(sc.mesh, opt);
  lv.set_field(sc.s, sc.tf);
  lv.set_lights({directional({1, 1, 1}, {0.25, 0.5, 0.75})});
  EXPECT_TRUE(lv.update().converged);
  for (std::size_t p = 0; p < sc.mesh->points.size(); ++p)
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(lv.light_rgb()[3 * p + c], 0.25 * (c + 1), 1e-6);

  const auto before = solve(sc, {directional({1, -0.5, 0.3})}, {0, 0, 0});
  const auto after = solve(sc, {directional({1, -0.5, 0.3})}, {4, 4, 4});
  const auto used = used_points(*sc.mesh);
  float lo = 1e30f, hi = -1e30f;
  for (std::size_t i = 0; i < before.size(); i += 3) {
    lo = std::min(lo, before[i]);
    hi = std::max(hi, before[i]);
  }
  for (std::size_t i = 0; i < after.size(); i += 3) {
    EXPECT_GE(after[i], lo - 1e-6f);
    EXPECT_LE(after[i], hi + 1e-6f);
  }
}

// One NaN scalar: its tets have no data (zero extinction), the light stays finite everywhere
// and so does the scattered colour.
TEST(LightScattering, NanVertexDoesNotSpread) {
  Scene sc;
  sc.s[sc.mesh->points.size() / 2] = std::nanf("");
  const auto rgb = solve(sc, {directional({1, 0.2, 0.1})}, {2, 2, 2});
  for (float v : rgb) ASSERT_TRUE(std::isfinite(v));
}

// The diffusion solve itself, fed a non-finite pre-diffusion value: the NaN point is left out
// of its neighbours' sums and itself takes their weighted mean, so nothing becomes NaN.
TEST(LightScattering, IterationExcludesNonFiniteValues) {
  const auto mesh = tet_block(4, 4, 4, {0, 0, 0}, {1, 1, 1});
  const render::lighting::Level1Topology topo(*mesh);
  const auto w = render::lighting::scatter_weights(*mesh, topo);
  const auto plan = render::lighting::plan_scatter(*mesh, topo, w);
  std::vector<float> pre(3 * mesh->points.size(), 0.5f);
  pre[3 * 30 + 1] = std::nanf("");
  pre[3 * 40] = INFINITY;
  std::vector<float> planned_pre, cur;
  render::lighting::to_plan_order(plan, pre, planned_pre);
  cur = planned_pre;
  render::lighting::ScatterSolve solve;
  for (int it = 0; it < 50; ++it) render::lighting::scatter_iteration(plan, planned_pre, {1, 1, 1}, cur, solve);
  std::vector<float> by_point;
  render::lighting::to_point_order(plan, cur, by_point);
  ASSERT_EQ(by_point.size(), pre.size());
  for (float v : by_point) {
    ASSERT_TRUE(std::isfinite(v));
    EXPECT_NEAR(v, 0.5f, 1e-6f);  // a constant field, with two holes in it, stays constant
  }
}

// The diffusion solve's inputs on Scene's mesh: a source per point (the field times 1, 2, 3 per
// channel) in the plan's order, and three different step sizes.
struct SweepScene {
  const Scene sc;
  const render::lighting::Level1Topology topo{*sc.mesh};
  const std::vector<float> w = render::lighting::scatter_weights(*sc.mesh, topo);
  const render::lighting::ScatterPlan plan = render::lighting::plan_scatter(*sc.mesh, topo, w);
  const std::array<double, 3> sigma{0.5, 2.0, 8.0};
  std::vector<float> pre, planned_pre;
  SweepScene() {
    pre.resize(3 * sc.mesh->points.size());
    for (std::size_t p = 0; p < sc.mesh->points.size(); ++p)
      for (int c = 0; c < 3; ++c) pre[3 * p + c] = static_cast<float>(sc.s[p] * (c + 1));
    render::lighting::to_plan_order(plan, pre, planned_pre);
  }
};

// An iteration done in pieces (a frame's budget ending inside it) gives the same values, bit for
// bit, as whole iterations, keeps the last finished iterate in place until it is done, and
// reports its residual only when its last block is done.
TEST(LightScattering, IterationInPiecesEqualsWholeIterations) {
  const SweepScene ss;
  const auto& plan = ss.plan;
  const auto& planned_pre = ss.planned_pre;
  const auto& sigma = ss.sigma;
  std::vector<float> whole = planned_pre, pieces = planned_pre;
  render::lighting::ScatterSolve whole_solve, pieces_solve;
  const std::size_t split[] = {1, 3, 2, 5, 16, 7};  // uneven pieces; those reaching past an iteration's end stop there
  std::size_t piece = 0;
  for (int it = 0; it < 5; ++it) {
    const std::vector<float> before = pieces;
    const double want = render::lighting::scatter_iteration(plan, planned_pre, sigma, whole, whole_solve);
    bool done = false;
    while (!done) {
      done = render::lighting::scatter_iteration_part(plan, planned_pre, sigma, pieces, pieces_solve, split[piece++ % 6]);
      if (!done) ASSERT_EQ(0, std::memcmp(before.data(), pieces.data(), before.size() * sizeof(float)));
    }
    EXPECT_EQ(pieces_solve.residual, want) << "iteration " << it;
    ASSERT_EQ(0, std::memcmp(whole.data(), pieces.data(), whole.size() * sizeof(float))) << "iteration " << it;
  }
  EXPECT_GT(piece, 10u);  // the iterations really were split
}

// Every point follows the Chebyshev recurrence, compared with the recurrence written out in
// double over the mesh's own edges: on a mesh of 343 points the plan's last slice is partial and
// its last blocks are empty (a block past the last point once redid the last slice, reading as
// the iterate before the last what its own block had already overwritten; the solve still
// converged, more slowly, and its iterates depended on the threads' timing).
TEST(LightScattering, IterationsFollowTheRecurrenceOnEveryPoint) {
  const auto mesh = tet_block(6, 6, 6, {0, 0, 0}, {1, 1, 1});
  const std::size_t np = mesh->points.size();
  const render::lighting::Level1Topology topo(*mesh);
  const std::vector<float> w = render::lighting::scatter_weights(*mesh, topo);
  const render::lighting::ScatterPlan plan = render::lighting::plan_scatter(*mesh, topo, w);
  ASSERT_NE(np % render::lighting::kScatterSlice, 0u);
  ASSERT_EQ(plan.chunk_begin[render::lighting::kScatterChunks - 1], np);  // an empty last block
  const std::array<double, 3> sigma{0.5, 1.0, 4.0};
  std::vector<float> pre(3 * np), planned_pre, planned, out;
  for (std::size_t p = 0; p < np; ++p)
    for (int c = 0; c < 3; ++c) pre[3 * p + c] = (p * 7 + static_cast<std::size_t>(c)) % 5 == 0 ? 1.0f : 0.1f;
  render::lighting::to_plan_order(plan, pre, planned_pre);
  planned = planned_pre;
  std::vector<double> x(pre.begin(), pre.end()), before = x, next(3 * np);
  std::array<double, 3> omega{};
  render::lighting::ScatterSolve solve;
  for (int k = 0; k < 8; ++k) {
    render::lighting::scatter_iteration(plan, planned_pre, sigma, planned, solve);
    render::lighting::chebyshev_weights(k, sigma, omega);
    for (std::size_t p = 0; p < np; ++p)
      for (std::size_t c = 0; c < 3; ++c) {
        double sum = 0, wsum = 0;
        for (auto e = topo.edge_offsets[p]; e < topo.edge_offsets[p + 1]; ++e) {
          sum += w[static_cast<std::size_t>(e)] * x[3 * static_cast<std::size_t>(topo.edge_ids[static_cast<std::size_t>(e)]) + c];
          wsum += w[static_cast<std::size_t>(e)];
        }
        const double jacobi = (pre[3 * p + c] + sigma[c] * sum) / (1 + sigma[c] * wsum);
        next[3 * p + c] = k == 0 ? jacobi : before[3 * p + c] + omega[c] * (jacobi - before[3 * p + c]);
      }
    before = x;
    x = next;
    render::lighting::to_point_order(plan, planned, out);
    double worst = 0;
    for (std::size_t i = 0; i < x.size(); ++i) worst = std::max(worst, std::fabs(x[i] - out[i]));
    EXPECT_LT(worst, 1e-5) << "iteration " << k + 1;
  }
}

// The solve against the equation itself: iterated to convergence, every point satisfies
// L_v = (L0_v + s sum_i w_i L_i) / (1 + s sum_i w_i) with the normalised weights of eq. 12.
// Chebyshev's acceleration is measured against plain Jacobi (omega = 1 throughout) on the same
// system: at these step sizes (up to s = 8, rho = 0.98) it needs 3x fewer iterations here.
TEST(LightScattering, IterationConvergesToTheImplicitStep) {
  const SweepScene ss;
  const Scene& sc = ss.sc;
  const auto& topo = ss.topo;
  const auto& w = ss.w;
  const auto& plan = ss.plan;
  const auto& pre = ss.pre;
  const auto& planned_pre = ss.planned_pre;
  const auto& sigma = ss.sigma;
  std::vector<float> planned = planned_pre, out;
  render::lighting::ScatterSolve solve;
  int iterations = 0;
  // 3e-6: about 12 units in the last place of the largest values (3); float iterates that read
  // only the previous iterate settle within a few, not on an exact fixed point.
  constexpr double kStop = 3e-6;
  while (render::lighting::scatter_iteration(plan, planned_pre, sigma, planned, solve) > kStop && iterations < 2000)
    ++iterations;
  // Plain Jacobi: every iteration the first of its solve.
  std::vector<float> jacobi = planned_pre;
  int jacobi_iterations = 0;
  for (render::lighting::ScatterSolve plain;
       render::lighting::scatter_iteration(plan, planned_pre, sigma, jacobi, plain) > kStop && jacobi_iterations < 5000;
       plain.restart())
    ++jacobi_iterations;
  EXPECT_LT(2 * iterations, jacobi_iterations);
  render::lighting::to_point_order(plan, planned, out);
  double worst = 0;
  for (std::size_t p = 0; p < sc.mesh->points.size(); ++p)
    for (int c = 0; c < 3; ++c) {
      double sum = 0, wsum = 0;
      for (auto s = topo.edge_offsets[p]; s < topo.edge_offsets[p + 1]; ++s) {
        sum += w[static_cast<std::size_t>(s)] * out[3 * static_cast<std::size_t>(topo.edge_ids[static_cast<std::size_t>(s)]) + c];
        wsum += w[static_cast<std::size_t>(s)];
      }
      const double expect = (pre[3 * p + c] + sigma[static_cast<std::size_t>(c)] * sum) / (1 + sigma[static_cast<std::size_t>(c)] * wsum);
      worst = std::max(worst, std::fabs(expect - out[3 * p + c]));
    }
  // The last iteration changed nothing by more than kStop; the equation's residual is of that size.
  std::printf("worst equation residual %.3g\n", worst);
  EXPECT_LT(worst, 3 * kStop);
  std::cout << "Chebyshev iterations: " << iterations << ", Jacobi: " << jacobi_iterations << "\n";
}

}  // namespace
}  // namespace penumbra::lighting_test
