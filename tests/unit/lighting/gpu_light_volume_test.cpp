// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/lighting/gpu_light_volume_test.cpp -- the GPU light solve against the CPU solve
//
// Runs on Mesa's llvmpipe where no GPU exists (surfaceless EGL). Both solves converge to their
// tolerances and are compared vertex by vertex. Agreement tolerance, per light:
//     level 0: |rho_gpu - rho_cpu| <= 1e-5 at every node;
//     level 1: |rho_gpu - rho_cpu| <= 3e-4 at every vertex, mean <= 2e-5.
// Why: the device computes in float32 what the CPU computes in double and stores as float; GLSL
// allows exp and log a few ULP, so a few 1e-7 relative per level-0 node or level-1 step, ~1e-5
// after the few hundred along a ray (measured on llvmpipe: <= 2e-6). Level 1 stops when a pass
// changes no vertex by more than propagation_tolerance (1e-4); rounding can make one solve run
// one pass more than the other, which moves vertices by up to that tolerance, hence three
// tolerances at a vertex. Scattering: Jacobi on the device, Gauss-Seidel on the CPU; each stops
// within 6 sigma_s scatter_tolerance max|L| of the exact step, so with scatter_tolerance = 1e-7
// the colour fields agree to 1e-4 max|L| beyond the level-1 difference.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>

#include "lighting/gpu_light_solver.h"
#include "lighting/level1_mesh.h"
#include "lighting_test_util.h"
#include "penumbra/core/error.h"
#include "penumbra/render/gpu_ray_caster.h"

namespace penumbra::lighting_test {
namespace {

constexpr double kRhoMaxTolerance = 3e-4;
constexpr double kRhoMeanTolerance = 2e-5;
constexpr double kLevel0Tolerance = 1e-5;

render::GpuOptions quiet() {
  render::GpuOptions o;
  o.log = [](const std::string&) {};
  return o;
}

struct Difference {
  double max = 0, mean = 0;
};

Difference compare(const std::vector<float>& a, const std::vector<float>& b, const std::vector<bool>* used = nullptr,
                   std::size_t stride = 1) {
  Difference d;
  std::size_t n = 0;
  EXPECT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
    if (used && !(*used)[i / stride]) continue;
    const double e = std::fabs(static_cast<double>(a[i]) - b[i]);
    d.max = std::max(d.max, e);
    d.mean += e;
    ++n;
  }
  if (n) d.mean /= static_cast<double>(n);
  return d;
}

class GpuLightVolume : public ::testing::Test {
protected:
  void SetUp() override {
    if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
    device = render::GpuDevice::open(quiet());
  }

  /// Solves on both, checks convergence and agreement of every light (level 0 and level 1) and
  /// of the colour field; returns the worst level-1 difference.
  Difference solve_both(const char* name, const std::shared_ptr<const TetMesh>& mesh, LightVolumeOptions opt,
                        const std::vector<float>& s, const TransferFunction& tf, const std::vector<Light>& lights,
                        std::unique_ptr<LightVolume>* gpu_out = nullptr) {
    using Clock = std::chrono::steady_clock;
    opt.device = nullptr;
    LightVolume cpu(mesh, opt);
    opt.device = device;
    auto gpu = std::make_unique<LightVolume>(mesh, opt);
    double ms[2] = {0, 0};
    int k = 0;
    for (LightVolume* lv : {&cpu, gpu.get()}) {
      lv->set_field(s, tf);
      lv->set_lights(lights);
      const auto t0 = Clock::now();
      const auto r = lv->update();
      ms[k++] = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      EXPECT_TRUE(r.converged) << name << (lv == &cpu ? " cpu" : " gpu") << " residual " << r.residual;
      EXPECT_EQ(r.lost_traces, 0u) << name;
    }
    const auto used = used_points(*mesh);
    Difference worst;
    for (std::size_t l = 0; l < lights.size(); ++l) {
      const Difference d0 = compare(cpu.level0_rho(l), gpu->level0_rho(l));
      const Difference d1 = compare(cpu.light_rho(l), gpu->light_rho(l), &used);
      EXPECT_LE(d0.max, kLevel0Tolerance) << name << " light " << l << " level 0";
      EXPECT_LE(d1.max, kRhoMaxTolerance) << name << " light " << l;
      EXPECT_LE(d1.mean, kRhoMeanTolerance) << name << " light " << l;
      worst.max = std::max(worst.max, d1.max);
      worst.mean = std::max(worst.mean, d1.mean);
      std::printf("[gpu-light] %s light %zu: level 0 max %.2g; level 1 max %.2g mean %.2g\n", name, l, d0.max, d1.max,
                  d1.mean);
    }
    double scale = 0;
    for (float v : cpu.light_rgb()) scale = std::max(scale, static_cast<double>(std::fabs(v)));
    const Difference drgb = compare(cpu.light_rgb(), gpu->light_rgb(), &used, 3);
    std::printf("[gpu-light] %s rgb max %.2g (of max %.3g); cpu %.1f ms, gpu %.1f ms (%zu tets)\n", name, drgb.max,
                scale, ms[0], ms[1], mesh->tets.size());
    last_rgb = drgb;
    last_rgb_scale = scale;
    if (gpu_out) *gpu_out = std::move(gpu);
    return worst;
  }

  std::shared_ptr<render::GpuDevice> device;
  Difference last_rgb;  ///< colour-field difference of the last solve_both
  double last_rgb_scale = 0;
};

// Homogeneous slab lit along +x: both equal exp(-1.5 x); the GPU to float32 rounding.
TEST_F(GpuLightVolume, HomogeneousSlabIsBeerLambert) {
  const auto mesh = tet_block(16, 6, 6, {0, 0, 0}, {2, 1, 1});
  LightVolumeOptions opt;
  opt.level0_resolution = 33;
  const auto s = field(*mesh, [](const Vec3d&) { return 0.0; });
  std::unique_ptr<LightVolume> gpu;
  solve_both("slab", mesh, opt, s, constant_tf(1.5), {directional({1, 0, 0})}, &gpu);
  const double worst = max_error_vs(gpu->light_rho(0), *mesh, [](const Vec3d& x) { return std::exp(-1.5 * x.x); });
  std::printf("[gpu-light] slab: max |rho_gpu - exp(-sigma x)| = %.2g\n", worst);
  EXPECT_LT(worst, 1e-5);
}

// Oblique light and a varying field through a ramp transfer function (the extinction table's
// pieces), two lights of different colours.
TEST_F(GpuLightVolume, ObliqueLightsInVaryingField) {
  const auto mesh = tet_block(10, 8, 8, {0, 0, 0}, {1.25, 1, 1});
  LightVolumeOptions opt;
  opt.level0_resolution = 24;
  const auto s = field(*mesh, [](const Vec3d& p) { return 0.5 + 0.6 * std::sin(4 * p.x) * std::cos(3 * p.y + p.z); });
  solve_both("varying", mesh, opt, s, ramp_tf(2.5),
             {directional({1, 0.4, 0.25}, {1, 0.8, 0.6}), directional({-0.3, -1, 0.5}, {0.2, 0.4, 1})});
}

// Light crosses the hole (level-0 values where traces leave the mesh).
TEST_F(GpuLightVolume, LightCrossesHole) {
  const auto mesh = prepare(fixtures::tet_block_with_hole(12));
  LightVolumeOptions opt;
  opt.level0_resolution = 33;
  const auto s = field(*mesh, [](const Vec3d&) { return 0.0; });
  solve_both("hole", mesh, opt, s, constant_tf(2.0), {directional({1, 0, 0}), directional({1, 0.3, 0.2})});
}

// A light along a face diagonal: rays along edges and boundary faces, whose projected edge
// values are rounding noise; both retry those walks with the noise snapped, so both follow
// Beer-Lambert at every vertex.
TEST_F(GpuLightVolume, DiagonalLightAlongBoundaryFaces) {
  const auto mesh = tet_block(8, 8, 4, {0, 0, 0}, {1, 1, 0.5});
  LightVolumeOptions opt;
  opt.level0_resolution = 17;
  const auto s = field(*mesh, [](const Vec3d&) { return 0.0; });
  std::unique_ptr<LightVolume> gpu;
  solve_both("diagonal", mesh, opt, s, constant_tf(1.2), {directional({1, 1, 0})}, &gpu);
  const double err = max_error_vs(gpu->light_rho(0), *mesh,
                                  [](const Vec3d& x) { return std::exp(-1.2 * std::sqrt(2.0) * std::min(x.x, x.y)); });
  EXPECT_LT(err, 1e-5);
}

// A box occluder: its shadow is exactly 0 on both.
TEST_F(GpuLightVolume, BoxOccluderShadow) {
  const auto mesh = tet_block(10, 10, 10, {0, 0, 0}, {1, 1, 1});
  LightVolumeOptions opt;
  opt.level0_resolution = 32;
  opt.occluders = {Bounds{{0.35, 0.35, 0.2}, {0.65, 0.65, 0.4}}};
  const auto s = field(*mesh, [](const Vec3d&) { return 0.0; });
  std::unique_ptr<LightVolume> gpu;
  solve_both("occluder", mesh, opt, s, constant_tf(0.8), {directional({0, 0, 1})}, &gpu);
  int shadowed = 0;
  for (std::size_t p = 0; p < mesh->points.size(); ++p) {
    const Vec3d& x = mesh->points[p];
    if (x.x >= 0.35 && x.x <= 0.65 && x.y >= 0.35 && x.y <= 0.65 && x.z >= 0.2) {
      EXPECT_EQ(gpu->light_rho(0)[p], 0.0f) << "point " << p;
      ++shadowed;
    }
  }
  EXPECT_GT(shadowed, 20);
}

// A point light inside a cell: every octant of the level-0 wavefront and the radial walks.
TEST_F(GpuLightVolume, PointLightInsideCell) {
  const auto mesh = tet_block(10, 10, 10, {0, 0, 0}, {1, 1, 1});
  LightVolumeOptions opt;
  opt.level0_resolution = 24;
  const auto s = field(*mesh, [](const Vec3d& p) { return p.x + 0.5 * p.y; });
  std::unique_ptr<LightVolume> gpu;
  const Vec3d P{0.437, 0.512, 0.463};
  solve_both("point", mesh, opt, s, constant_tf(1.0), {point_light(P)}, &gpu);
  const double worst = max_error_vs(gpu->light_rho(0), *mesh, [&](const Vec3d& x) { return std::exp(-length(x - P)); });
  std::printf("[gpu-light] point: max |rho_gpu - exp(-sigma r)| = %.2g\n", worst);
  EXPECT_LT(worst, 1e-4);
}

// Scattering on: the colour fields agree to 1e-4 of their maximum beyond the level-1 agreement.
TEST_F(GpuLightVolume, ScatteringAgrees) {
  const auto mesh = tet_block(8, 8, 8, {0, 0, 0}, {1, 1, 1});
  LightVolumeOptions opt;
  opt.level0_resolution = 16;
  opt.sigma_s = {0.5, 1.0, 2.0};
  opt.scatter_tolerance = 1e-7;
  const auto s = field(*mesh, [](const Vec3d& p) { return 0.5 + 0.5 * std::sin(4 * p.x) * std::cos(3 * p.y + p.z); });
  const std::vector<Light> lights = {directional({1, 0.3, -0.2}, {1.0, 0.5, 0.2}),
                                     point_light({0.3, 1.4, 0.6}, {0.1, 0.4, 0.9})};
  std::unique_ptr<LightVolume> gpu;
  const Difference rho = solve_both("scatter", mesh, opt, s, ramp_tf(3.0), lights, &gpu);
  EXPECT_LE(last_rgb.max, 1e-4 * last_rgb_scale + 2 * rho.max);
  EXPECT_LE(last_rgb.mean, 1e-4 * last_rgb_scale + 2 * rho.mean);
  // The scattered field differs from the unscattered one (the stage ran on the device).
  std::vector<float> pre(gpu->light_rgb().size(), 0.0f);
  for (std::size_t l = 0; l < lights.size(); ++l)
    for (std::size_t p = 0; p < mesh->points.size(); ++p)
      for (int c = 0; c < 3; ++c) pre[3 * p + c] += static_cast<float>(gpu->light_rho(l)[p] * lights[l].color[c]);
  EXPECT_GT(compare(pre, gpu->light_rgb()).max, 1e-3);
}

// Hard cases: a strongly graded mesh (cells 1000x apart) at a fixed step (no adaptive steps)
// far above the CFL limit of its smallest cell, and sigma L = 1e4 with a NaN vertex and scattering: both stay within
// [0, 1], finite and without denormals on the device, and agree with the CPU.
TEST_F(GpuLightVolume, HardCasesAgree) {
  auto m = fixtures::block(fixtures::BlockCells::tets, 30, 2, 2, {0, 0, 0}, {1, 0.2, 0.2});
  const double r = std::pow(1000.0, 1.0 / 29);
  for (std::size_t p = 0; p < m.point_count(); ++p) {
    const int i = static_cast<int>(std::lround(m.xyz[3 * p] * 30));
    m.xyz[3 * p] = (std::pow(r, i) - 1) / (std::pow(r, 30) - 1);
  }
  const auto graded = prepare(m);
  LightVolumeOptions opt;
  opt.level0_resolution = 32;
  opt.level1_adaptive_step = false;
  opt.level1_step = 0.02;
  opt.level1_max_passes = 400;
  solve_both("graded", graded, opt, field(*graded, [](const Vec3d& p) { return p.x; }), ramp_tf(3.0),
             {directional({1, 0.1, 0.05})});

  const auto mesh = tet_block(10, 4, 4, {0, 0, 0}, {1, 1, 1});
  auto s = field(*mesh, [](const Vec3d&) { return 0.0; });
  s[s.size() / 2] = std::nanf("");
  LightVolumeOptions dark;
  dark.level0_resolution = 16;
  dark.sigma_a = 1e4;
  dark.sigma_s = {1, 1, 1};
  std::unique_ptr<LightVolume> gpu;
  solve_both("absorbing", mesh, dark, s, constant_tf(1.0), {directional({1, 0.2, 0.1})}, &gpu);
  for (const auto* values : {&gpu->light_rho(0), &gpu->level0_rho(0), &gpu->light_rgb()})
    for (float v : *values) {
      ASSERT_TRUE(std::isfinite(v));
      EXPECT_NE(std::fpclassify(v), FP_SUBNORMAL);
      EXPECT_GE(v, 0.0f);
      EXPECT_LE(v, 1.0f);
    }
}

// The budget in work units: one unit per call still converges, to the same field as one
// unlimited call, and a moved light is recomputed alone.
TEST_F(GpuLightVolume, BudgetAndIncrementalUpdates) {
  const auto mesh = tet_block(8, 8, 8, {0, 0, 0}, {1, 1, 1});
  LightVolumeOptions opt;
  opt.level0_resolution = 16;
  opt.sigma_s = {1.0, 1.0, 1.0};
  opt.device = device;
  const auto s = field(*mesh, [](const Vec3d& p) { return p.z; });
  const auto tf = ramp_tf(2.0);
  std::vector<Light> lights = {directional({0.2, 0.1, 1}), point_light({0.5, 0.5, -0.5})};
  LightVolume whole(mesh, opt), steps(mesh, opt);
  for (LightVolume* lv : {&whole, &steps}) {
    lv->set_field(s, tf);
    lv->set_lights(lights);
  }
  EXPECT_TRUE(whole.update().converged);
  int calls = 0;
  render::LightBudget one;
  one.max_work_units = 1;
  for (; calls < 2000; ++calls) {
    const auto r = steps.update(one);
    EXPECT_LE(r.work_units, 1);
    if (r.converged) break;
  }
  EXPECT_LT(calls, 2000);
  EXPECT_GT(calls, 4);
  EXPECT_LE(compare(whole.light_rgb(), steps.light_rgb()).max, 1e-3);
  // A time budget: whole GPU passes, each call makes progress, and the light converges.
  LightVolume timed(mesh, opt);
  timed.set_field(s, tf);
  timed.set_lights(lights);
  render::LightBudget short_frames;
  short_frames.max_ms = 0.5;
  int timed_calls = 0;
  for (; timed_calls < 2000; ++timed_calls) {
    const auto r = timed.update(short_frames);
    EXPECT_TRUE(r.work_units >= 1 || r.resample_ms > 0) << "call " << timed_calls << " made no progress";
    if (r.converged) break;
  }
  EXPECT_LT(timed_calls, 2000);
  EXPECT_LE(compare(whole.light_rgb(), timed.light_rgb()).max, 1e-3);
  lights[1].vector = {0.5, -0.5, 0.5};
  whole.set_lights(lights);
  const auto r = whole.update();
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.lights_recomputed, 1);
}

// A mesh beyond the device's configured memory limit is a clear error, not a crash.
TEST_F(GpuLightVolume, MeshBeyondTheMemoryLimitIsAClearError) {
  render::GpuOptions o = quiet();
  o.memory_limit_bytes = 10000;
  LightVolumeOptions opt;
  opt.device = render::GpuDevice::open(o);
  try {
    LightVolume lv(tet_block(6, 6, 6, {0, 0, 0}, {1, 1, 1}), opt);
    ADD_FAILURE() << "a mesh needing more than the limit was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::out_of_memory);
    EXPECT_NE(std::string(e.what()).find("GPU light volume: the mesh (1296 tets"), std::string::npos) << e.what();
  }
}

// Without a GPU backend no device can be opened, so the GPU solve cannot be asked for: the error
// names the reason.
TEST(GpuLightVolumeUnavailable, ClearErrorWithoutBackend) {
  if (render::gpu_backend_compiled()) GTEST_SKIP() << "built with the GPU backend";
  try {
    render::GpuDevice::open(quiet());
    ADD_FAILURE() << "a device opened without a GPU backend";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::backend_unavailable);
    EXPECT_NE(std::string(e.what()).find("PNB_ENABLE_EGL=OFF"), std::string::npos) << e.what();
  }
  // The solver behind options.device says so too.
  const auto mesh = tet_block(2, 2, 2, {0, 0, 0}, {1, 1, 1});
  const render::lighting::Level1Topology topology(*mesh);
  try {
    render::lighting::GpuLightSolver solver(nullptr, *mesh, topology, {}, {});
    ADD_FAILURE() << "a GPU light solver was built without a GPU backend";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::backend_unavailable);
    EXPECT_NE(std::string(e.what()).find("options.device"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace penumbra::lighting_test
