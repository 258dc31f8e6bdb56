// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/occlusion/gpu_cone_tracer_test.cpp -- the GPU cone tracer against ConeTracer
//
// Runs on Mesa's llvmpipe where no GPU exists (surfaceless EGL, no display needed).
//
// Tolerance. Both paths read the same float32 pyramid and walk the same schedule; the GPU does the
// arithmetic in float32 instead of float64. Positions relative to the bounds centre carry a rounding
// of ~6e-8 of the domain (~1e-5 of a grid cell at 100 cells), which moves each trilinear fetch of
// the Gaussian-blurred extinction by a relative ~1e-5 at most; the trapezoid sum of <= ~100 terms
// adds ~1e-6 relative; exp(-depth) turns a relative depth error e into an absolute transmittance
// error T depth e <= e / (e_Euler) . So 1e-4 absolute leaves an order of magnitude of margin while
// still catching any difference of algorithm (a wrong inheritance, weight or level shows at 1e-2).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "occlusion_test_util.h"
#include "penumbra/core/error.h"
#include "occlusion/gpu_occlusion.h"

namespace penumbra::occlusion_test {
namespace {

constexpr double kAgreement = 1e-4;

GpuOptions quiet() {
  GpuOptions o;
  o.log = [](const std::string&) {};
  return o;
}

class GpuConeTracerTest : public ::testing::Test {
protected:
  void SetUp() override {
    if (!gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
    device = GpuDevice::open(quiet());
  }
  std::shared_ptr<GpuDevice> device;
};

std::vector<Vec3d> random_points(std::size_t n, const Vec3d& lo, const Vec3d& hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3d> p(n);
  for (auto& x : p) x = {lo.x + u(rng) * (hi.x - lo.x), lo.y + u(rng) * (hi.y - lo.y), lo.z + u(rng) * (hi.z - lo.z)};
  return p;
}

// Largest |gpu - cpu| over the points.
double max_difference(const std::vector<float>& gpu, const std::vector<Vec3d>& points,
                      const std::function<double(const Vec3d&)>& cpu) {
  EXPECT_EQ(gpu.size(), points.size());
  double worst = 0;
  for (std::size_t i = 0; i < points.size() && i < gpu.size(); ++i)
    worst = std::max(worst, std::fabs(gpu[i] - cpu(points[i])));
  return worst;
}

TEST_F(GpuConeTracerTest, HomogeneousMediumIsExactForEveryApertureAndSplit) {
  // As the CPU test: T = exp(-tau (L - h0)); float32 depth accumulation is the only error.
  const double tau = 1.0;
  const ExtinctionPyramid p(grid(121, -6, 6, [&](const Vec3d&) { return tau; }), {PyramidQuantity::extinction});
  const GpuExtinctionPyramid gp(device, p);
  const std::vector<Vec3d> points = {{0.1, -0.2, 0.05}, {-1.3, 0.7, 1.1}, {0.9, 0.4, -1.2}};
  for (double aperture : {0.5, 2.0, 10.0, 20.0, 30.0})
    for (int splits : {1, 3, 7}) {
      ConeOptions o = ConeOptions::occlusion(aperture, splits);
      o.length = 1.5;
      const GpuConeTracer t(gp, o);
      const double want = std::exp(-tau * (o.length - t.host().gap()));
      const std::vector<float> got = t.transmittance(ConeTarget::towards_eye({3, 4, 5}), points);
      for (std::size_t i = 0; i < points.size(); ++i)
        EXPECT_NEAR(got[i], want, 2e-5 * want) << "aperture " << aperture << " splits " << splits << " point " << i;
    }
}

TEST_F(GpuConeTracerTest, RandomPointsOnAResampledSceneAgreeWithTheCpu) {
  // A real scene: a tet block whose scalar is the distance to an off-centre point, resampled
  // through a "ball" transfer function (an opaque-ish ball with a soft rim, empty elsewhere),
  // filtered as opacity (the default). Points everywhere, including outside the mesh bounds.
  const auto mesh = tet_block(12, {-1, -1, -1}, {1, 1, 1});
  const Vec3d centre{0.2, -0.1, 0.15};
  const auto scalars = field(*mesh, [&](const Vec3d& x) { return length(x - centre); });
  const ExtinctionPyramid p(resample_extinction(*mesh, scalars, ball_tf(12.0, 0.55, 0.2), 48));
  const GpuExtinctionPyramid gp(device, p);
  const auto points = random_points(2000, {-1.1, -1.1, -1.1}, {1.1, 1.1, 1.1}, 7);
  const Vec3d eye{2.5, -3.0, 4.0};
  double worst = 0;
  for (LevelSelection level : {LevelSelection::continuous, LevelSelection::thesis})
    for (int splits : {1, 3, 7}) {
      ConeOptions o = ConeOptions::occlusion(25.0, splits);
      o.level = level;
      const GpuConeTracer t(gp, o);
      const std::vector<float> gpu = t.transmittance(ConeTarget::towards_eye(eye), points);
      const double d =
          max_difference(gpu, points, [&](const Vec3d& x) { return directional_occlusion(t.host(), x, eye); });
      const bool thesis = level == LevelSelection::thesis;
      EXPECT_LT(d, kAgreement) << "occlusion, splits " << splits << ", thesis levels " << thesis;
      // Not a comparison of ones: the ball hides a good share of the points from the eye.
      const auto dark = std::count_if(gpu.begin(), gpu.end(), [](float v) { return v < 0.5f; });
      EXPECT_GT(dark, 100) << "splits " << splits << ", thesis levels " << thesis;
      worst = std::max(worst, d);
    }
  const GpuConeTracer s(gp, ConeOptions::shadow(2.0, 3));
  const ShadowLight lights[] = {{ShadowLight::Kind::directional, {-0.3, 0.2, -1.0}},
                                {ShadowLight::Kind::point, {0.9, 0.8, 1.0}},
                                {ShadowLight::Kind::spot, {-0.9, 0.9, 0.9}, {1, -1, -1}, 35.0}};
  for (const ShadowLight& light : lights) {
    const std::vector<float> gpu = s.transmittance(ConeTarget::towards_light(light), points);
    double d = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (light.kind == ShadowLight::Kind::spot) {
        // Points within float rounding of the spot's edge may fall on either side of it.
        const Vec3d to = points[i] - light.vector;
        const double c = dot(to, normalize(light.spot_direction)) / length(to);
        if (std::fabs(c - std::cos(35.0 * kPi / 180.0)) < 1e-5) continue;
      }
      d = std::max(d, std::fabs(gpu[i] - shadow_transmittance(s.host(), light, points[i])));
    }
    EXPECT_LT(d, kAgreement) << "shadow, light kind " << static_cast<int>(light.kind);
    worst = std::max(worst, d);
  }
  std::printf("[gpu-cone] %zu random points, AO splits 1/3/7 (both level selections) and 3 lights: max |GPU - CPU| = %.2e\n", points.size(),
              worst);
}

TEST_F(GpuConeTracerTest, ThinOccluderCastsTheSameShadow) {
  // A plate two cells thick between the points and the lights (as the CPU occluder test): behind
  // it little light passes; beside it, all. Splits 3 and 7 keep the plate sharper than one cone, on
  // the GPU as on the CPU, and the values agree with the CPU tracer.
  const double h = 2.0 / 96;
  const ExtinctionPyramid p(grid(97, -1, 1, [&](const Vec3d& x) {
    return std::fabs(x.z - 0.3) <= h && std::fabs(x.x) < 0.5 && std::fabs(x.y) < 0.5 ? 1e4 : 0.0;
  }));
  const GpuExtinctionPyramid gp(device, p);
  const std::vector<Vec3d> points = {{0, 0, -0.4}, {0.2, -0.1, -0.2}, {0.85, 0.0, -0.4}, {0, 0.9, -0.3}};
  const ShadowLight sun{ShadowLight::Kind::directional, {0, 0, -1}};
  const ShadowLight lamp{ShadowLight::Kind::point, {0, 0, 0.8}};
  for (int splits : {1, 3, 7}) {
    ConeOptions o = ConeOptions::shadow(2.0, splits);
    o.length = 1.3;
    const GpuConeTracer t(gp, o);
    for (const ShadowLight& light : {sun, lamp}) {
      const std::vector<float> got = t.transmittance(ConeTarget::towards_light(light), points);
      for (std::size_t i = 0; i < points.size(); ++i)
        EXPECT_NEAR(got[i], shadow_transmittance(t.host(), light, points[i]), kAgreement) << splits << " " << i;
      // Behind the plate: dark, not black -- its blurred profile (width ~3 cells) is sampled by the
      // trapezoid rule every 2.5 sigma0, which under-integrates it (the CPU gives the same 0.05-0.07).
      EXPECT_LT(got[0], 0.1) << "behind the plate, splits " << splits;
      EXPECT_LT(got[1], 0.1) << "behind the plate, splits " << splits;
      if (light.kind == ShadowLight::Kind::directional) {
        EXPECT_GT(got[2], 0.99) << "beside the plate, splits " << splits;
        EXPECT_GT(got[3], 0.99) << "beside the plate, splits " << splits;
      }
    }
  }
  // A wide cone through the plate's centre: more splits, less light leaking (as on the CPU).
  std::vector<float> wide;
  for (int splits : {1, 3, 7}) {
    ConeOptions o = ConeOptions::occlusion(25.0, splits);
    o.length = 1.3;
    wide.push_back(GpuConeTracer(gp, o).transmittance(ConeTarget::towards_eye({0, 0, 5}), {{0, 0, -0.5}})[0]);
  }
  EXPECT_LT(wide[1], wide[0]);
  EXPECT_LT(wide[2], wide[1]);
}

TEST_F(GpuConeTracerTest, ObjectSpaceGridAndMeshPointsMatchTheCpu) {
  const auto mesh = tet_block(8, {0, 0, 0}, {2, 1, 1});
  const auto scalars = field(*mesh, [](const Vec3d& x) { return length(x - Vec3d{1.2, 0.5, 0.6}); });
  const ExtinctionPyramid p(resample_extinction(*mesh, scalars, ball_tf(8.0, 0.45, 0.15), 40));
  const GpuExtinctionPyramid gp(device, p);
  const GpuConeTracer t(gp, ConeOptions::occlusion(20.0, 3));
  const Vec3d eye{-2, 3, 4};
  auto ao = [&](const Vec3d& x) { return directional_occlusion(t.host(), x, eye); };

  // The pre-illumination grid: same nodes as PreIlluminationVolume, same values.
  const PreIlluminationVolume cpu_volume(p.bounds(), 17, ao);
  const GpuPreIllumination gpu_volume = t.pre_illumination(ConeTarget::towards_eye(eye), p.bounds(), 17);
  ASSERT_EQ(gpu_volume.dims, cpu_volume.dims());
  double worst = 0;
  for (std::size_t i = 0; i < cpu_volume.values().size(); ++i)
    worst = std::max(worst, static_cast<double>(std::fabs(gpu_volume.values[i] - cpu_volume.values()[i])));
  EXPECT_LT(worst, kAgreement);
  EXPECT_NEAR(gpu_volume.sample({0.7, 0.33, 0.81}), cpu_volume.sample({0.7, 0.33, 0.81}), kAgreement);
  EXPECT_GT(gpu_volume.build_ms, 0.0);

  // Per mesh point, directly and through the volume (both dispatches on the device).
  const std::vector<float> direct = t.at_mesh_points(ConeTarget::towards_eye(eye), mesh);
  const std::vector<float> want_direct = evaluate_at_points(*mesh, ao);
  const std::vector<float> sampled = t.at_mesh_points(ConeTarget::towards_eye(eye), mesh, 17);
  const std::vector<float> want_sampled = evaluate_at_points(*mesh, [&](const Vec3d& x) { return cpu_volume.sample(x); });
  ASSERT_EQ(direct.size(), mesh->points.size());
  ASSERT_EQ(sampled.size(), mesh->points.size());
  double worst_direct = 0, worst_sampled = 0, darkest = 1;
  for (std::size_t i = 0; i < direct.size(); ++i) {
    worst_direct = std::max(worst_direct, static_cast<double>(std::fabs(direct[i] - want_direct[i])));
    worst_sampled = std::max(worst_sampled, static_cast<double>(std::fabs(sampled[i] - want_sampled[i])));
    darkest = std::min(darkest, static_cast<double>(direct[i]));
  }
  EXPECT_LT(worst_direct, kAgreement);
  EXPECT_LT(worst_sampled, kAgreement);
  EXPECT_LT(darkest, 0.7);  // the ball does occlude something: the comparison is not of ones
  std::printf("[gpu-cone] grid %dx%dx%d max |GPU - CPU| %.2e; %zu mesh points %.2e direct, %.2e via the grid\n",
              gpu_volume.dims[0], gpu_volume.dims[1], gpu_volume.dims[2], worst, direct.size(), worst_direct,
              worst_sampled);

  // A new step: the same objects take the new pyramid.
  const ExtinctionPyramid empty(resample_extinction(*mesh, scalars, constant_tf(0.0), 40));
  GpuExtinctionPyramid gp2(device, p);
  const GpuConeTracer stale(gp2, ConeOptions::occlusion(20.0, 3));
  gp2.update(empty);
  const GpuConeTracer t2(gp2, ConeOptions::occlusion(20.0, 3));
  for (float v : t2.at_mesh_points(ConeTarget::towards_eye(eye), mesh)) ASSERT_EQ(v, 1.0f);
  // A tracer made before the update has the old schedule: a clear error, not stale reads.
  try {
    stale.at_mesh_points(ConeTarget::towards_eye(eye), mesh);
    ADD_FAILURE() << "a stale tracer ran";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_operation) << e.what();
  }
}

TEST_F(GpuConeTracerTest, BadInputIsAClearError) {
  const ExtinctionPyramid p(grid(9, 0, 1, [](const Vec3d&) { return 1.0; }));
  EXPECT_THROW(GpuExtinctionPyramid(nullptr, p), Error);
  const ExtinctionPyramid none;
  EXPECT_THROW(GpuExtinctionPyramid(device, none), Error);
  const GpuExtinctionPyramid gp(device, p);
  ConeOptions o;
  o.splits = 2;
  EXPECT_THROW(GpuConeTracer(gp, o), Error);  // the CPU tracer's checks
  const GpuConeTracer t(gp, ConeOptions::occlusion());
  EXPECT_THROW(t.pre_illumination(ConeTarget::towards_eye({0, 0, 5}), p.bounds(), 1), Error);
  EXPECT_THROW(t.at_mesh_points(ConeTarget::towards_eye({0, 0, 5}), nullptr), Error);
  EXPECT_TRUE(t.transmittance(ConeTarget::towards_eye({0, 0, 5}), {}).empty());
  // A point at the eye, and non-finite points: as the CPU, fully transmitted.
  const auto v = t.transmittance(ConeTarget::towards_eye({0.5, 0.5, 0.5}), {{0.5, 0.5, 0.5}, {NAN, 0, 0}});
  EXPECT_EQ(v[0], 1.0f);
  EXPECT_EQ(v[1], 1.0f);
}

// Without the GPU backend compiled in, or without EGL at run time, the GPU tracer reports
// Error(backend_unavailable) instead of crashing.
TEST(GpuConeTracerUnavailable, NoEglIsAClearError) {
  const ExtinctionPyramid p(grid(9, 0, 1, [](const Vec3d&) { return 1.0; }));
  if (!gpu_backend_compiled()) {
    try {
      GpuExtinctionPyramid gp(nullptr, p);
      ADD_FAILURE() << "a build without EGL constructed a GPU pyramid";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::backend_unavailable) << e.what();
      EXPECT_NE(std::string(e.what()).find("PNB_ENABLE_EGL=OFF"), std::string::npos) << e.what();
    }
    return;
  }
  GpuOptions o = quiet();
  o.egl_library = "/nonexistent/elsewhere/libEGL.so.1";
  try {
    GpuExtinctionPyramid gp(GpuDevice::open(o), p);
    ADD_FAILURE() << "a missing libEGL gave a device";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::backend_unavailable) << e.what();
  }
}

}  // namespace
}  // namespace penumbra::occlusion_test

namespace penumbra::occlusion_test {
namespace {

// The pyramid filtered on the device against ExtinctionPyramid: identical lattices, and values
// that agree to float32 summation. Compared as what the cones integrate: for extinction, tau
// relative to the largest tau (15-tap float32 sums: ~1e-7, bound 1e-5); for opacity, the per-cell
// opacity 1 - exp(-tau l) (the filtered quantity, float32 on both paths, bound 1e-5); for
// step_opacity the same with l the level's slab thickness kConeStepSigmas sigma_l.
TEST_F(GpuConeTracerTest, PyramidBuiltOnTheDeviceMatchesTheCpu) {
  const auto mesh = tet_block(10, {0, 0, 0}, {2, 1, 1.5});
  const auto scalars = field(*mesh, [](const Vec3d& x) { return length(x - Vec3d{1.2, 0.5, 0.6}); });
  const ExtinctionGrid g = resample_extinction(*mesh, scalars, ball_tf(40.0, 0.5, 0.1), 41);
  for (PyramidQuantity q : {PyramidQuantity::extinction, PyramidQuantity::opacity, PyramidQuantity::step_opacity}) {
    const ExtinctionPyramid cpu(g, {q});
    const GpuPyramidLevels gpu = gpu_build_pyramid_levels(device, g, {q});
    ASSERT_EQ(static_cast<int>(gpu.levels.size()), cpu.levels());
    const double cell = g.mean_spacing();
    double worst = 0, largest = 0;
    for (int k = 0; k < cpu.levels(); ++k) {
      const PyramidLevel &c = cpu.level(k), &d = gpu.levels[static_cast<std::size_t>(k)];
      ASSERT_EQ(d.dims, c.dims) << "level " << k;
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(d.lo[a], c.lo[a]);
        EXPECT_EQ(d.spacing[a], c.spacing[a]);
      }
      EXPECT_EQ(d.sigma, c.sigma);
      ASSERT_EQ(d.tau.size(), c.tau.size());
      const double l = q == PyramidQuantity::step_opacity ? kConeStepSigmas * c.sigma : cell;
      for (std::size_t i = 0; i < c.tau.size(); ++i) {
        largest = std::max(largest, static_cast<double>(c.tau[i]));
        const double diff = q == PyramidQuantity::extinction
                                ? std::fabs(d.tau[i] - c.tau[i])
                                : std::fabs(std::exp(-d.tau[i] * l) - std::exp(-c.tau[i] * l));
        worst = std::max(worst, diff);
      }
    }
    if (q == PyramidQuantity::extinction) worst /= largest;
    std::printf("[gpu-pyramid] %s: %d levels, max difference %.2e (%s); build %.1f ms (filter %.1f ms) vs CPU %.1f ms\n",
                q == PyramidQuantity::extinction ? "extinction" : (q == PyramidQuantity::opacity ? "opacity" : "step_opacity"),
                cpu.levels(), worst, q == PyramidQuantity::extinction ? "relative tau" : "slab opacity", gpu.build_ms, gpu.filter_ms,
                cpu.build_ms());
    EXPECT_LT(worst, 1e-5);
    EXPECT_GT(largest, 10.0);  // the ball is there
  }
}

}  // namespace
}  // namespace penumbra::occlusion_test
