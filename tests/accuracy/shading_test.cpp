// SPDX-License-Identifier: BSD-3-Clause
// Shading of the emitted colour (penumbra/render/shading.h) against closed forms.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>

#include "penumbra/core/error.h"
#include "scenes.h"

namespace penumbra {
namespace {

using fixtures::BlockCells;

render::RenderOptions full_integral() {
  render::RenderOptions opts;
  opts.early_termination_opacity = 1.0;
  return opts;
}

// Only the light field: ambient 1, no diffuse or specular term.
render::Shading light_only(const std::vector<float>& light_rgb) {
  render::Shading s;
  s.model = render::LightingModel::light_volume;
  s.light_rgb = &light_rgb;
  s.ambient = 1.0;
  s.diffuse = 0.0;
  s.specular = 0.0;
  return s;
}

// Pixels are stored as float (rounding ~6e-8 of values <= 1): 1e-6 leaves a margin while any
// wrong factor or misplaced interpolation changes pixels by > 1e-3.
constexpr double kPixelTolerance = 1e-6;

TEST(Shading, ConstantLightScalesTheEmissionPerChannel) {
  const auto owned = fixtures::block(BlockCells::tets, 5, 4, 4, {0, 0, 0}, {1, 1, 1});
  const auto mesh = test::prepare(owned);
  render::CpuRayCaster caster(mesh);
  const auto values = fixtures::sample(owned, [](double x, double y, double z) { return x + 0.5 * y * z; });
  const std::vector<float> scalars(values.begin(), values.end());
  render::TransferFunction tf;
  tf.colors = {{0.0, 0.9, 0.1, 0.2}, {1.5, 0.1, 0.8, 0.6}};
  tf.opacities = {{0.0, 0.5}, {1.5, 2.5}};
  const auto cam = render::Camera::orbit(mesh->bounds, 30, 25, 35, 24, 20);
  const render::Image plain = caster.render(scalars, tf, cam, full_integral());
  std::vector<float> light(3 * mesh->points.size());
  const float l[3] = {0.5f, 1.0f, 2.0f};
  for (std::size_t i = 0; i < light.size(); ++i) light[i] = l[i % 3];
  render::RenderOptions opts = full_integral();
  opts.shading = light_only(light);
  const render::Image lit = caster.render(scalars, tf, cam, opts);
  int covered = 0;
  for (std::size_t p = 0; p < plain.rgba.size(); p += 4) {
    covered += plain.rgba[p + 3] > 0.01f;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(lit.rgba[p + c], l[c] * plain.rgba[p + c], kPixelTolerance) << p;
    EXPECT_EQ(lit.rgba[p + 3], plain.rgba[p + 3]) << "light must not change opacity";
  }
  EXPECT_GT(covered, 100);
}

TEST(Shading, LightLinearAlongTheRayMatchesClosedForm) {
  // White homogeneous medium of extinction sigma lit by L(x) = z, which per-point linear
  // interpolation represents exactly. Along a ray entering at t0 with L = A and dL/dt = B, the
  // colour is int_0^D sigma (A + B u) exp(-sigma u) du
  //   = A (1 - e^(-sigma D)) + B ((1 - e^(-sigma D)) / sigma - D e^(-sigma D)).
  const Vec3d lo{0, 0, 0}, hi{1, 1, 1};
  const auto owned = fixtures::block(BlockCells::tets, 6, 6, 6, lo, hi);
  const auto mesh = test::prepare(owned);
  render::CpuRayCaster caster(mesh);
  const std::vector<float> scalars(mesh->points.size(), 0.0f);
  std::vector<float> light(3 * mesh->points.size());
  for (std::size_t i = 0; i < mesh->points.size(); ++i)
    for (int c = 0; c < 3; ++c) light[3 * i + c] = static_cast<float>(mesh->points[i].z);
  const double sigma = 1.3;
  const auto cam = render::Camera::look_at({1.7, -0.8, 2.4}, {0.5, 0.5, 0.5}, {0, 0, 1}, 40, 24, 24);
  render::RenderOptions opts = full_integral();
  opts.shading = light_only(light);
  const render::Image img = caster.render(scalars, test::constant_tf(sigma), cam, opts);
  int inside = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const render::Ray ray = cam.primary_ray(x, y);
      const double d = test::chord(lo, hi, ray.origin, ray.direction);
      if (d <= 0) continue;
      ++inside;
      // Entry depth: the far exit minus the chord, from the box slabs.
      double t_exit = 1e300;
      for (int a = 0; a < 3; ++a)
        if (ray.direction[a] != 0)
          t_exit = std::min(t_exit, std::max((lo[a] - ray.origin[a]) / ray.direction[a],
                                             (hi[a] - ray.origin[a]) / ray.direction[a]));
      const double t0 = t_exit - d;
      const double a_light = ray.origin.z + ray.direction.z * t0, b_light = ray.direction.z;
      const double e = std::exp(-sigma * d);
      const double expect = a_light * (1 - e) + b_light * ((1 - e) / sigma - d * e);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(img.pixel(x, y)[c], expect, kPixelTolerance) << x << "," << y;
    }
  EXPECT_GT(inside, 200);
}

TEST(Shading, ImageSpaceLightAgreesWithPointLightWhereBothAreExact) {
  // L(x) = (z, 1 - z/2, 1): linear, so interpolating it from the points and evaluating it at
  // every segment end give the same segments, hence the same picture; only the path differs.
  const auto owned = fixtures::block(BlockCells::tets, 5, 5, 5, {0, 0, 0}, {1, 1, 1});
  const auto mesh = test::prepare(owned);
  render::CpuRayCaster caster(mesh);
  const auto values = fixtures::sample(owned, [](double x, double y, double z) { return x + 0.4 * y - 0.3 * z; });
  const std::vector<float> scalars(values.begin(), values.end());
  render::TransferFunction tf;
  tf.colors = {{-0.3, 0.9, 0.2, 0.1}, {1.4, 0.1, 0.6, 0.9}};
  tf.opacities = {{-0.3, 0.6}, {1.4, 2.0}};
  std::vector<float> light(3 * mesh->points.size());
  for (std::size_t i = 0; i < mesh->points.size(); ++i) {
    const double z = mesh->points[i].z;
    light[3 * i] = static_cast<float>(z);
    light[3 * i + 1] = static_cast<float>(1 - 0.5 * z);
    light[3 * i + 2] = 1.0f;
  }
  const auto cam = render::Camera::orbit(mesh->bounds, 40, 30, 35, 32, 32);
  render::RenderOptions by_points = full_integral();
  by_points.shading = light_only(light);
  render::RenderOptions by_samples = by_points;
  by_samples.shading.light_rgb = nullptr;
  std::atomic<long> calls{0};
  by_samples.shading.light_at = [&calls](const Vec3d& x, double rgb[3]) {
    ++calls;
    rgb[0] = x.z;
    rgb[1] = 1 - 0.5 * x.z;
    rgb[2] = 1;
  };
  const render::Image a = caster.render(scalars, tf, cam, by_points);
  const render::Image b = caster.render(scalars, tf, cam, by_samples);
  // Float light values per point against doubles per sample: 1e-6 covers the difference.
  for (std::size_t i = 0; i < a.rgba.size(); ++i) EXPECT_NEAR(a.rgba[i], b.rgba[i], 1e-6) << i;
  EXPECT_GT(calls.load(), 32 * 32);  // evaluated along the rays, not per pixel
}

// One pixel looking straight down -z at a block whose scalar is x (normal +-x).
struct PhongScene {
  fixtures::OwnedMesh owned = fixtures::block(BlockCells::tets, 4, 4, 4, {0, 0, 0}, {1, 1, 1});
  std::shared_ptr<const render::TetMesh> mesh = test::prepare(owned);
  render::CpuRayCaster caster{mesh};
  render::Camera cam = render::Camera::look_at({0.37, 0.41, 3}, {0.37, 0.41, 0.5}, {0, 1, 0}, 10, 1, 1);
  double sigma = 0.7;

  double render_red(const std::vector<float>& scalars, const render::Shading& shading) const {
    render::RenderOptions opts = full_integral();
    opts.shading = shading;
    return caster.render(scalars, test::constant_tf(sigma), cam, opts).pixel(0, 0)[0];
  }
  std::vector<float> field_x() const {
    const auto v = fixtures::sample(owned, [](double x, double, double) { return x; });
    return {v.begin(), v.end()};
  }
};

TEST(Shading, PhongFactorOfALinearFieldMatchesTheFormula) {
  PhongScene scene;
  const double unlit = 1.0 - std::exp(-scene.sigma * 1.0);  // white emission through depth 1
  render::Shading s;
  s.model = render::LightingModel::phong;
  s.ambient = 0.2;
  s.diffuse = 0.5;
  s.specular = 0.4;
  s.shininess = 8;
  // Light along +x: N.L = 1; the view is +z, so H = (1, 0, 1)/sqrt(2) and N.H = 1/sqrt(2).
  s.light_direction = {1, 0, 0};
  EXPECT_NEAR(scene.render_red(scene.field_x(), s), (0.2 + 0.5 + 0.4 / 16.0) * unlit, kPixelTolerance);
  // Headlight: the light comes from the eye, perpendicular to the normal: ambient only.
  s.light_direction = {0, 0, 0};
  EXPECT_NEAR(scene.render_red(scene.field_x(), s), 0.2 * unlit, kPixelTolerance);
  // A constant field has no normal: lit as if facing the light, without a highlight.
  const std::vector<float> flat(scene.mesh->points.size(), 0.5f);
  EXPECT_NEAR(scene.render_red(flat, s), (0.2 + 0.5) * unlit, kPixelTolerance);
}

TEST(Shading, BadOptionsAreRefusedWithAClearError) {
  PhongScene scene;
  const auto scalars = scene.field_x();
  auto expect_error = [&](const render::Shading& s, const std::string& needle) {
    try {
      scene.render_red(scalars, s);
      ADD_FAILURE() << "expected an error mentioning " << needle;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  render::Shading s;
  s.model = render::LightingModel::light_volume;
  expect_error(s, "needs light_rgb");
  const std::vector<float> short_light(5, 1.0f);
  s.light_rgb = &short_light;
  expect_error(s, "3 per point");
  s.model = render::LightingModel::phong;
  s.ambient = -1;
  expect_error(s, "ambient");
  s.ambient = 0.3;
  s.light_direction = {std::nan(""), 0, 0};
  expect_error(s, "light_direction");
}

}  // namespace
}  // namespace penumbra
